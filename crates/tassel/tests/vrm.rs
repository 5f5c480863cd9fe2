//! VRM spring bones in the core: the spec's update checked against the spec's equations
//! worked by hand (f64), centre space, bad settings, and fixed-mode hitches.

use glam::{DVec3, Quat, Vec3};
use tassel::dynamics::vrm::*;
use tassel::{Pose, Skeleton, SkeletonBuilder, Transform};

/// root (origin) → head at (0, 1, 0) whose tail is 1 m along its local +X.
fn one_joint() -> Skeleton {
    let mut b = SkeletonBuilder::new();
    b.add("root", None, Transform::IDENTITY);
    b.add(
        "head",
        Some(0),
        Transform::from_translation(Vec3::new(0.0, 1.0, 0.0)),
    );
    b.build().unwrap().0
}

struct Run {
    skeleton: Skeleton,
    rig: VrmRig,
    state: VrmState,
    pose: Pose,
}

impl Run {
    fn new(skeleton: Skeleton, bones: &VrmSpringBones, options: VrmOptions) -> Self {
        let rig = VrmRig::new(&skeleton, bones, options).unwrap();
        let state = VrmState::new(&rig);
        let pose = Pose::rest(&skeleton);
        Self {
            skeleton,
            rig,
            state,
            pose,
        }
    }

    fn frame(&mut self, component: Transform, dt: f32) -> &Pose {
        self.pose.locals.copy_from_slice(self.skeleton.rest());
        self.pose
            .update_models(&self.skeleton, &Transform::IDENTITY)
            .unwrap();
        VrmJob {
            skeleton: &self.skeleton,
            rig: &self.rig,
            state: &mut self.state,
            component,
            dt,
            locals: &mut self.pose.locals,
            models: &mut self.pose.models,
        }
        .run()
        .unwrap();
        &self.pose
    }
}

fn spring(joint: VrmJoint, colliders: Vec<usize>) -> VrmSpring {
    VrmSpring {
        name: "s".into(),
        joints: vec![joint],
        collider_groups: colliders,
        center: None,
    }
}

#[test]
fn spec_mode_matches_the_equations_worked_by_hand() {
    let (k, g, drag, dt) = (2.0f64, 3.0f64, 0.25f64, 0.1f64);
    let joint = VrmJoint {
        joint: 1,
        tail: VrmTail::Local(Vec3::X),
        hit_radius: 0.1,
        stiffness: k as f32,
        gravity_power: g as f32,
        gravity_dir: Vec3::NEG_Y,
        drag_force: drag as f32,
        limit: None,
    };
    // A sphere on the root, placed where the tail swings through.
    let bones = VrmSpringBones {
        colliders: vec![VrmCollider {
            joint: 0,
            shape: VrmShape::Sphere {
                offset: Vec3::new(0.55, 0.0, -0.1),
                radius: 0.3,
                inside: false,
            },
        }],
        collider_groups: vec![VrmColliderGroup {
            name: "g".into(),
            colliders: vec![0],
        }],
        springs: vec![spring(joint, vec![0])],
        ..Default::default()
    };
    let mut run = Run::new(one_joint(), &bones, VrmOptions::spec());
    // The character: still in frames 0 and 1, then 0.1 m along +Z per frame.
    let root_z = |f: usize| if f < 2 { 0.0 } else { 0.1 * (f - 1) as f64 };

    // By hand (f64): head at (0, 1, z); rest direction +X (root and head unrotated).
    let normalize = |v: DVec3| v / v.length();
    let mut cur = DVec3::new(1.0, 1.0, 0.0);
    let mut prev = cur;
    let mut hits = 0;
    run.frame(Transform::IDENTITY, 0.0);
    for f in 1..=4 {
        let z = root_z(f);
        let head = DVec3::new(0.0, 1.0, z);
        let inertia = (cur - prev) * (1.0 - drag);
        let stiffness = DVec3::X * (k * dt);
        let external = DVec3::NEG_Y * (g * dt);
        let mut next = head + normalize(cur + inertia + stiffness + external - head);
        // Sphere at (0.55, 0, −0.1 + z) in world, radius 0.3 + hit radius 0.1.
        let center = DVec3::new(0.55, 0.0, -0.1 + z);
        let delta = next - center;
        let dist = delta.length() - 0.4;
        if dist < 0.0 {
            hits += 1;
            next -= normalize(delta) * dist;
            next = head + normalize(next - head);
        }
        prev = cur;
        cur = next;

        let comp = Transform::from_translation(Vec3::new(0.0, 0.0, z as f32));
        let pose = run.frame(comp, dt as f32).clone();
        let world = comp * pose.models[1];
        let tail = world.transform_point(Vec3::X).as_dvec3();
        assert!(
            (tail - cur).length() < 1e-6,
            "frame {f}: tail {tail} vs hand-computed {cur} ({:.2e} m)",
            (tail - cur).length()
        );
        // The stored state agrees too (no centre: world space).
        let stored = run.state.tails_world(&run.rig, &comp, &pose.models)[0].as_dvec3();
        assert!((stored - cur).length() < 1e-6, "frame {f}: state {stored}");
    }
    // The collider really acted (so the check above covers the push).
    assert!(hits > 0, "the sphere was never reached");
}

#[test]
fn center_space_carries_the_tails_with_the_centre() {
    // With the spring's centre on the root, moving the whole character leaves the swing
    // exactly as if it stood still (the tails ride along in centre space).
    let joint = VrmJoint {
        joint: 1,
        tail: VrmTail::Local(Vec3::X),
        stiffness: 0.5,
        gravity_power: 1.0,
        drag_force: 0.3,
        ..Default::default()
    };
    let mut with_center = spring(joint, vec![]);
    with_center.center = Some(0);
    let bones_c = VrmSpringBones {
        springs: vec![with_center],
        ..Default::default()
    };
    let bones_w = VrmSpringBones {
        springs: vec![spring(joint, vec![])],
        ..Default::default()
    };
    let mut moving = Run::new(one_joint(), &bones_c, VrmOptions::spec());
    let mut still = Run::new(one_joint(), &bones_w, VrmOptions::spec());
    moving.frame(Transform::IDENTITY, 0.0);
    still.frame(Transform::IDENTITY, 0.0);
    let mut swung = 0.0f32;
    for f in 1..=120 {
        let comp = Transform::from_translation(Vec3::new((f as f32 * 0.2).sin(), 0.0, 0.0));
        let a = moving.frame(comp, 1.0 / 60.0).locals[1].rotation;
        let b = still.frame(Transform::IDENTITY, 1.0 / 60.0).locals[1].rotation;
        // Compare where the bone points (quaternion angles are too coarse in f32).
        let gap = (a * Vec3::X - b * Vec3::X).length();
        assert!(gap < 1e-5, "frame {f}: {gap}");
        swung = swung.max(b.angle_between(Quat::IDENTITY));
    }
    // Gravity did swing it (so equality is not trivial).
    assert!(swung > 0.3, "{swung}");
    // Without a centre the same motion does change the swing.
    let mut world = Run::new(one_joint(), &bones_w, VrmOptions::spec());
    world.frame(Transform::IDENTITY, 0.0);
    let mut differs = 0.0f32;
    for f in 1..=120 {
        let comp = Transform::from_translation(Vec3::new((f as f32 * 0.2).sin(), 0.0, 0.0));
        let a = world.frame(comp, 1.0 / 60.0).locals[1].rotation;
        let b = still.frame(Transform::IDENTITY, 1.0 / 60.0).locals[1].rotation;
        differs = differs.max((a * Vec3::X - b * Vec3::X).length());
    }
    assert!(differs > 0.05, "{differs}");
}

#[test]
fn bad_settings_are_named() {
    let sk = one_joint();
    let base = VrmJoint {
        joint: 1,
        tail: VrmTail::Local(Vec3::X),
        ..Default::default()
    };
    let cases: Vec<(VrmSpringBones, &str)> = vec![
        (
            VrmSpringBones {
                springs: vec![spring(VrmJoint { joint: 7, ..base }, vec![])],
                ..Default::default()
            },
            "joint 7 does not exist",
        ),
        (
            VrmSpringBones {
                springs: vec![spring(
                    VrmJoint {
                        hit_radius: -0.1,
                        ..base
                    },
                    vec![],
                )],
                ..Default::default()
            },
            "hitRadius -0.1 must be ≥ 0",
        ),
        (
            VrmSpringBones {
                springs: vec![spring(
                    VrmJoint {
                        gravity_dir: Vec3::new(f32::NAN, -1.0, 0.0),
                        ..base
                    },
                    vec![],
                )],
                ..Default::default()
            },
            "gravityDir",
        ),
        (
            VrmSpringBones {
                springs: vec![spring(base, vec![]), spring(base, vec![])],
                ..Default::default()
            },
            "already in VRM spring 0",
        ),
        (
            VrmSpringBones {
                springs: vec![spring(
                    VrmJoint {
                        tail: VrmTail::Joint(0),
                        ..base
                    },
                    vec![],
                )],
                ..Default::default()
            },
            "is not below the joint",
        ),
        (
            VrmSpringBones {
                springs: vec![spring(base, vec![3])],
                ..Default::default()
            },
            "collider group 3 does not exist",
        ),
        (
            VrmSpringBones {
                colliders: vec![VrmCollider {
                    joint: 0,
                    shape: VrmShape::Sphere {
                        offset: Vec3::ZERO,
                        radius: -1.0,
                        inside: false,
                    },
                }],
                ..Default::default()
            },
            "radius -1 must be finite and ≥ 0",
        ),
    ];
    for (bones, want) in cases {
        let e = VrmRig::new(&sk, &bones, VrmOptions::spec())
            .expect_err(want)
            .to_string();
        assert!(e.contains(want), "'{e}' does not say '{want}'");
    }
}

#[test]
fn fixed_mode_survives_hitches_bad_steps_and_teleports() {
    let joint = VrmJoint {
        joint: 1,
        tail: VrmTail::Local(Vec3::X),
        stiffness: 1.0,
        gravity_power: 1.0,
        ..Default::default()
    };
    let bones = VrmSpringBones {
        springs: vec![spring(joint, vec![])],
        ..Default::default()
    };
    let options = VrmOptions {
        mode: VrmMode::Fixed,
        teleport_distance: 5.0,
        ..Default::default()
    };
    let mut run = Run::new(one_joint(), &bones, options);
    run.frame(Transform::IDENTITY, 0.0);
    for dt in [f32::NAN, -1.0, f32::INFINITY] {
        let mut locals = run.skeleton.rest().to_vec();
        let mut models = Pose::rest(&run.skeleton).models;
        let e = VrmJob {
            skeleton: &run.skeleton,
            rig: &run.rig,
            state: &mut run.state,
            component: Transform::IDENTITY,
            dt,
            locals: &mut locals,
            models: &mut models,
        }
        .run();
        assert!(e.is_err(), "dt {dt} accepted");
    }
    let resets = run.state.reset_count();
    run.frame(Transform::IDENTITY, 10.0);
    let far = Transform::from_translation(Vec3::new(100.0, 0.0, 0.0));
    let pose = run.frame(far, 1.0 / 60.0).clone();
    assert_eq!(run.state.reset_count(), resets + 1, "the teleport resets");
    let tail = (far * pose.models[1]).transform_point(Vec3::X);
    assert!(tail.is_finite());
    // Back at the rest direction right after the teleport.
    assert!(tail.abs_diff_eq(Vec3::new(101.0, 1.0, 0.0), 1e-4), "{tail}");
}

#[test]
fn same_inputs_same_bits() {
    let run_once = || {
        let joint = VrmJoint {
            joint: 1,
            tail: VrmTail::Local(Vec3::X),
            stiffness: 0.7,
            gravity_power: 0.4,
            ..Default::default()
        };
        let bones = VrmSpringBones {
            springs: vec![spring(joint, vec![])],
            ..Default::default()
        };
        let mut run = Run::new(
            one_joint(),
            &bones,
            VrmOptions {
                mode: VrmMode::Fixed,
                ..Default::default()
            },
        );
        let mut bits = Vec::new();
        for f in 0..300 {
            let comp = Transform::from_translation(Vec3::new((f as f32 * 0.1).sin(), 0.0, 0.0));
            let q = run.frame(comp, 1.0 / 75.0).locals[1].rotation;
            bits.extend(q.to_array().map(f32::to_bits));
        }
        bits
    };
    assert_eq!(run_once(), run_once());
}

#[test]
fn a_bone_belongs_to_one_solver() {
    use tassel::dynamics::chain::ChainSettings;
    use tassel::dynamics::RigSettings;
    use tassel::CharacterSim;
    // A chain rooted at "root" turns "root" toward "head"; a VRM spring on "root" too.
    let rig = RigSettings {
        chains: vec![ChainSettings {
            name: "c".into(),
            root: "root".into(),
            ..Default::default()
        }],
        ..Default::default()
    };
    let bones = VrmSpringBones {
        springs: vec![spring(
            VrmJoint {
                joint: 0,
                tail: VrmTail::Joint(1),
                ..Default::default()
            },
            vec![],
        )],
        ..Default::default()
    };
    let e = CharacterSim::with_vrm(one_joint(), &rig, &bones, VrmOptions::spec())
        .expect_err("shared bone")
        .to_string();
    assert!(
        e.contains("bone 'root' is simulated by a VRM spring and by a chain"),
        "{e}"
    );
    // Without the chain it runs, and the spring turns the root.
    let mut sim = CharacterSim::with_vrm(
        one_joint(),
        &RigSettings::default(),
        &bones,
        VrmOptions::spec(),
    )
    .unwrap();
    let rest = one_joint().rest().to_vec();
    sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
    let side = Transform::from_translation(Vec3::new(0.5, 0.0, 0.0));
    let pose = sim.frame(&rest, side, 1.0 / 60.0).unwrap();
    assert!(pose.locals[0].rotation.angle_between(Quat::IDENTITY) > 1e-3);
}

/// The specification applies each collider a spring lists through its groups, so one
/// listed twice (group 0 and group 1 both hold collider 0, and the spring lists group 0
/// twice) acts three times, in group order; it used to be deduplicated (issue 15).
#[test]
fn a_collider_listed_twice_acts_twice() {
    let sphere = VrmCollider {
        joint: 0,
        shape: VrmShape::Sphere {
            offset: Vec3::new(1.0, 1.0, 0.0),
            radius: 0.1,
            inside: false,
        },
    };
    let plane = VrmCollider {
        joint: 0,
        shape: VrmShape::Plane {
            offset: Vec3::ZERO,
            normal: Vec3::Y,
        },
    };
    let bones = VrmSpringBones {
        colliders: vec![sphere, plane],
        collider_groups: vec![
            VrmColliderGroup {
                name: "a".into(),
                colliders: vec![0, 1],
            },
            VrmColliderGroup {
                name: "b".into(),
                colliders: vec![0],
            },
        ],
        springs: vec![spring(
            VrmJoint {
                joint: 1,
                tail: VrmTail::Local(Vec3::X),
                ..VrmJoint::default()
            },
            vec![0, 1, 0],
        )],
        ..Default::default()
    };
    let rig = VrmRig::new(&one_joint(), &bones, VrmOptions::spec()).unwrap();
    let range = rig.links[0].colliders.clone();
    assert_eq!(&rig.link_colliders[range], &[0, 1, 0, 0, 1]);
}
