//! Bone cloth (seed 004) against invariants: the skirt stays out of the legs through the
//! demo, a hanging cloth settles with bounded energy, structural lengths hold.

use glam::{Quat, Vec3};
use tassel::builtin::{self, DemoScript};
use tassel::collide::{PlacedCollider, Shape};
use tassel::dynamics::cloth::{
    ClothJob, ClothRig, ClothSettings, ClothState, ConstraintKind, SurfaceCollision,
};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::math::{closest_params_segment_segment, closest_point_on_segment};
use tassel::{CharacterSim, Transform};
use tassel::{LocalToModelJob, Pose};
use tassel::{Skeleton, SkeletonBuilder};

/// Distance from segment `a`–`b` to a collider's core, minus its radius (< 0: inside).
fn segment_clearance(a: Vec3, b: Vec3, col: &PlacedCollider) -> f32 {
    let t = &col.transform;
    match col.shape {
        Shape::Capsule { radius, length } => {
            let axis = t.rotation * Vec3::Y * (0.5 * length);
            let (e0, e1) = (t.translation - axis, t.translation + axis);
            let (s, u) = closest_params_segment_segment(a, b, e0, e1);
            (a + (b - a) * s - (e0 + (e1 - e0) * u)).length() - radius
        }
        Shape::Sphere { radius, .. } => {
            (closest_point_on_segment(t.translation, a, b) - t.translation).length() - radius
        }
        _ => f32::MAX,
    }
}

#[test]
fn skirt_stays_out_of_the_legs_through_the_demo() {
    let c = builtin::character();
    let sk = &c.skeleton;
    let mut sim = CharacterSim::new(sk.clone(), &c.rig).unwrap();
    let script = DemoScript;
    let mut animator = script.animator(&c);
    let mut locals = sk.rest().to_vec();
    let dt = 1.0 / 60.0;
    let legs: Vec<usize> = ["thigh_l", "thigh_r", "shin_l", "shin_r"]
        .iter()
        .map(|n| {
            c.rig
                .colliders
                .iter()
                .position(|col| col.name == *n)
                .unwrap()
        })
        .collect();
    let skirt: Vec<Vec<usize>> = (0..8)
        .map(|k| {
            (0..4)
                .map(|i| sk.find(&format!("skirt_{k}_{i}")).unwrap())
                .collect()
        })
        .collect();
    let frames = (DemoScript::DURATION * 60.0).round() as usize;
    let (mut worst_point, mut worst_segment, mut worst_cloth) = (0.0_f32, 0.0_f32, 0.0_f32);
    let mut contacts = 0usize;
    for f in 0..=frames {
        let m = script.at(f as f32 * dt);
        let step = if f == 0 { 0.0 } else { dt };
        script
            .pose(&c, &mut animator, &m, step, &mut locals)
            .unwrap();
        let pose = sim.frame(&locals, m.component, step).unwrap();
        // The bones as a viewer shows them (world space), and the cloth's own points.
        let world: Vec<Vec3> = pose
            .models
            .iter()
            .map(|t| m.component.transform_point(t.translation))
            .collect();
        let placed = sim.cloth_state().placed_colliders();
        for &li in &legs {
            let col = &placed[li];
            for k in 0..8 {
                let next = (k + 1) % 8;
                for i in 0..4 {
                    let p = world[skirt[k][i]];
                    let pen = col.penetration(p, 0.0);
                    worst_point = worst_point.max(pen);
                    // Segments: down the chain and across to the next chain.
                    if i + 1 < 4 {
                        let d = -segment_clearance(p, world[skirt[k][i + 1]], col);
                        worst_segment = worst_segment.max(d);
                    }
                    let d = -segment_clearance(p, world[skirt[next][i]], col);
                    worst_segment = worst_segment.max(d);
                    if d > -0.03 {
                        contacts += 1;
                    }
                }
            }
            for &p in sim.cloth_state().world_positions() {
                worst_cloth = worst_cloth.max(col.penetration(p, 0.0));
            }
        }
    }
    println!(
        "skirt vs legs over {frames} frames: worst point {worst_point:.5} m, segment {worst_segment:.5} m, cloth point {worst_cloth:.5} m; {contacts} near contacts"
    );
    assert!(
        contacts > 0,
        "the legs never came near the skirt: the test tests nothing"
    );
    assert!(
        worst_point <= 1e-3,
        "a skirt bone ended {worst_point} m inside a leg"
    );
    assert!(
        worst_segment <= 1e-3,
        "a skirt segment ended {worst_segment} m inside a leg"
    );
    assert!(
        worst_cloth <= 1e-3,
        "a cloth point ended {worst_cloth} m inside a leg"
    );
}

/// `chains` chains of `bones` bones each, roots in a row along X under "root", each
/// chain pointing along `dir` with segment length `seg`.
fn sheet(chains: usize, bones: usize, seg: f32, dir: Vec3) -> (Skeleton, Vec<[String; 2]>) {
    let mut b = SkeletonBuilder::new();
    let root = b.add("root", None, Transform::IDENTITY);
    b.add("mover", Some(root), Transform::IDENTITY);
    let mut pairs = Vec::new();
    for c in 0..chains {
        let mut p = b.add(
            format!("c{c}_0"),
            Some(root),
            Transform::from_translation(Vec3::new(c as f32 * seg, 2.0, 0.0)),
        );
        for i in 1..bones {
            p = b.add(
                format!("c{c}_{i}"),
                Some(p),
                Transform::from_translation(dir * seg),
            );
        }
        pairs.push([format!("c{c}_0"), format!("c{c}_{}", bones - 1)]);
    }
    (b.build().unwrap().0, pairs)
}

struct Rig {
    sk: Skeleton,
    rig: ClothRig,
    state: ClothState,
}

impl Rig {
    fn new(sk: Skeleton, settings: RigSettings) -> Self {
        let rig = ClothRig::new(&sk, &settings).unwrap();
        let state = ClothState::new(&rig);
        Self { sk, rig, state }
    }

    fn frame(&mut self, locals: &[Transform], dt: f32) -> Pose {
        let mut pose = Pose::rest(&self.sk);
        pose.locals.copy_from_slice(locals);
        LocalToModelJob {
            skeleton: &self.sk,
            root: Transform::IDENTITY,
            locals: &pose.locals,
            models: &mut pose.models,
        }
        .run()
        .unwrap();
        ClothJob {
            skeleton: &self.sk,
            rig: &self.rig,
            state: &mut self.state,
            component: Transform::IDENTITY,
            dt,
            locals: &mut pose.locals,
            models: &mut pose.models,
            level: None,
        }
        .run()
        .unwrap();
        pose
    }
}

#[test]
fn hanging_cloth_settles_with_bounded_energy_over_100k_steps() {
    // Starts horizontal (chains along +Z) and falls to hang from its pinned top row.
    let (sk, pairs) = sheet(6, 6, 0.1, Vec3::Z);
    let settings = RigSettings {
        cloths: vec![ClothSettings {
            name: "sheet".into(),
            chains: pairs,
            resistance: 0.02,
            ..Default::default()
        }],
        ..Default::default()
    };
    let mut r = Rig::new(sk.clone(), settings);
    let rest = sk.rest().to_vec();
    let h = 1.0 / 120.0;
    let g = 9.81_f32;
    let mut prev: Vec<Vec3> = Vec::new();
    let mut e0 = None;
    let mut e_max = f32::MIN;
    let mut last_kinetic = 0.0;
    for step in 0..100_000 {
        r.frame(&rest, h);
        let pos = r.state.world_positions().to_vec();
        assert!(pos.iter().all(|p| p.is_finite()), "NaN at step {step}");
        if !prev.is_empty() {
            // Energy per unit mass of the free points: ½v² + g·y.
            let mut kinetic = 0.0;
            let mut energy = 0.0;
            for (p, q) in pos.iter().zip(&prev) {
                let v = (*p - *q) / h;
                kinetic += 0.5 * v.length_squared();
                energy += 0.5 * v.length_squared() + g * p.y;
            }
            let e_start = *e0.get_or_insert(energy);
            e_max = e_max.max(energy - e_start);
            last_kinetic = kinetic;
        }
        prev = pos;
    }
    println!("hanging cloth: energy rose at most {e_max:.4} J/kg over its start; final kinetic {last_kinetic:.2e}");
    // A damped system released from rest never gains energy (tolerance for the
    // position-projection noise), and ends at rest.
    assert!(e_max < 0.05, "energy rose by {e_max} J/kg");
    assert!(last_kinetic < 1e-6, "still moving: {last_kinetic}");
    // It hangs: the free row's points are below the pinned row.
    let pos = r.state.world_positions();
    assert!(pos.iter().all(|p| p.y <= 2.0 + 1e-4));
    assert!(pos.iter().any(|p| p.y < 1.6), "the sheet did not fall");
}

#[test]
fn structural_lengths_hold_within_5_percent_with_4_iterations() {
    let (sk, pairs) = sheet(8, 8, 0.08, Vec3::Z);
    let settings = RigSettings {
        cloths: vec![ClothSettings {
            name: "sheet".into(),
            chains: pairs,
            iterations: 4,
            force_length_limit: false,
            ..Default::default()
        }],
        ..Default::default()
    };
    let mut r = Rig::new(sk.clone(), settings);
    let rest = sk.rest().to_vec();
    let mut worst = 0.0_f32;
    for _ in 0..600 {
        r.frame(&rest, 1.0 / 60.0);
        let pos = r.state.world_positions();
        for c in r.rig.constraints(0) {
            if matches!(
                c.kind,
                ConstraintKind::StructuralVertical | ConstraintKind::StructuralHorizontal
            ) {
                let l = (pos[c.a as usize] - pos[c.b as usize]).length();
                worst = worst.max((l - c.length).abs() / c.length);
            }
        }
    }
    println!(
        "structural length error, worst over 10 s: {:.2} %",
        100.0 * worst
    );
    assert!(
        worst < 0.05,
        "structural lengths off by {:.1} %",
        100.0 * worst
    );
}

/// A hanging sheet of 3 chains with wide quads and a sphere driven through the middle of
/// its upper-left quad along +Z: the sphere is smaller than the quad, so only the surface
/// test can stop it. Returns the ball's signed distance from the quad's plane (same sign
/// convention as at the start, where it is −0.3 m: behind) after the run.
fn sphere_through_sheet(mode: SurfaceCollision) -> f32 {
    let (sk, pairs) = sheet(3, 3, 0.3, Vec3::NEG_Y);
    let settings = RigSettings {
        cloths: vec![ClothSettings {
            name: "sheet".into(),
            chains: pairs,
            radius: 0.0,
            segment_collision: true,
            surface_collision: mode,
            colliders: vec!["ball".into()],
            ..Default::default()
        }],
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "ball".into(),
            bone: "mover".into(),
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            shape: Shape::Sphere {
                radius: 0.08,
                inside: false,
            },
        }],
        ..Default::default()
    };
    let mut r = Rig::new(sk.clone(), settings);
    let mover = sk.find("mover").unwrap();
    let mut locals = sk.rest().to_vec();
    let start = Vec3::new(0.15, 2.0 - 0.15, -0.3);
    let dt = 1.0 / 60.0;
    let ids = r.rig.quads(0)[0];
    let side = |pos: &[Vec3], ball: Vec3| {
        let q = ids.map(|i| pos[i as usize]);
        let n = (q[1] - q[0]).cross(q[3] - q[0]).normalize();
        n.dot(ball - q[0])
    };
    let mut sign = 0.0;
    let mut ball = start;
    for f in 0..=60 {
        ball = start + Vec3::Z * (0.6 * f as f32 / 60.0);
        locals[mover].translation = ball;
        r.frame(&locals, dt);
        if f == 0 {
            sign = side(r.state.world_positions(), ball).signum();
        }
    }
    -(side(r.state.world_positions(), ball) * sign)
}

#[test]
fn surface_collision_stops_a_ball_between_the_points() {
    // The quad is 0.3 m wide, the ball 0.16 m across: its centre passes 0.15 m from every
    // corner and edge, so points and segments alone never touch it.
    let through = sphere_through_sheet(SurfaceCollision::Off);
    assert!(
        through > 0.0,
        "without the surface test the ball passes: {through}"
    );
    let held = sphere_through_sheet(SurfaceCollision::PushPull);
    assert!(
        held <= -0.08 + 1e-3,
        "the ball should stay behind the quad, 0.08 m clear: {held}"
    );
}

#[test]
fn teleport_resets_to_the_animated_pose() {
    let (sk, pairs) = sheet(4, 4, 0.1, Vec3::Z);
    let settings = RigSettings {
        cloths: vec![ClothSettings {
            name: "sheet".into(),
            chains: pairs,
            teleport_distance: 1.0,
            ..Default::default()
        }],
        ..Default::default()
    };
    let rig = ClothRig::new(&sk, &settings).unwrap();
    let mut state = ClothState::new(&rig);
    let run = |component: Transform, state: &mut ClothState| {
        let mut pose = Pose::rest(&sk);
        ClothJob {
            skeleton: &sk,
            rig: &rig,
            state,
            component,
            dt: 1.0 / 60.0,
            locals: &mut pose.locals,
            models: &mut pose.models,
            level: None,
        }
        .run()
        .unwrap();
    };
    for _ in 0..30 {
        run(Transform::IDENTITY, &mut state);
    }
    assert_eq!(state.reset_count(), 0);
    let far = Transform::from_translation(Vec3::new(50.0, 0.0, 0.0));
    run(far, &mut state);
    assert_eq!(state.reset_count(), 1);
    // Right after the reset the cloth sagged by at most one frame of fall from the rest
    // pose (moved with the character), not 50 m of swing.
    let rest = Pose::rest(&sk);
    for c in 0..4 {
        for i in 0..4 {
            let j = sk.find(&format!("c{c}_{i}")).unwrap();
            let target = far.transform_point(rest.models[j].translation);
            let got = state.world_positions()[c * 4 + i];
            assert!(
                (got - target).length() < 0.02,
                "point {c},{i}: {got} vs {target}"
            );
        }
    }
}

#[test]
fn bad_cloth_settings_are_errors_naming_the_problem() {
    let (sk, pairs) = sheet(3, 3, 0.1, Vec3::Z);
    let make = |f: &dyn Fn(&mut ClothSettings)| {
        let mut s = ClothSettings {
            name: "sheet".into(),
            chains: pairs.clone(),
            ..Default::default()
        };
        f(&mut s);
        let rig = RigSettings {
            cloths: vec![s],
            ..Default::default()
        };
        ClothRig::new(&sk, &rig)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let e = make(&|s| s.chains[1][1] = "c1_9".into());
    assert!(e.contains("c1_9"), "{e}");
    let e = make(&|s| s.radius = -0.1);
    assert!(e.contains("radius"), "{e}");
    let e = make(&|s| s.resistance = f32::NAN);
    assert!(e.contains("resistance"), "{e}");
    let e = make(&|s| s.chains[0] = ["c1_0".into(), "c0_2".into()]);
    assert!(e.contains("not below"), "{e}");
    let e = make(&|s| s.chains.truncate(1));
    assert!(e.contains("two chains"), "{e}");
    let e = make(&|s| s.colliders = vec!["nothing".into()]);
    assert!(e.contains("nothing"), "{e}");
    // A bone on a cloth and a chain at once.
    let c = builtin::character();
    let mut rig = c.rig.clone();
    rig.chains.push(tassel::dynamics::chain::ChainSettings {
        name: "double".into(),
        root: "skirt_0_0".into(),
        ..Default::default()
    });
    let e = CharacterSim::new(c.skeleton.clone(), &rig)
        .unwrap_err()
        .to_string();
    assert!(e.contains("skirt_0_"), "{e}");
}

fn hanging(f: &dyn Fn(&mut ClothSettings)) -> Rig {
    // 5 chains of 5 bones hanging straight down from a row along X.
    let (sk, pairs) = sheet(5, 5, 0.1, Vec3::NEG_Y);
    let mut s = ClothSettings {
        name: "sheet".into(),
        chains: pairs,
        resistance: 0.05,
        ..Default::default()
    };
    f(&mut s);
    Rig::new(
        sk,
        RigSettings {
            cloths: vec![s],
            ..Default::default()
        },
    )
}

#[test]
fn hardness_one_gives_the_animated_pose() {
    let mut r = hanging(&|s| {
        s.hardness = 1.0;
        s.wind.acceleration = Vec3::new(0.0, 0.0, 5.0);
    });
    let rest = r.sk.rest().to_vec();
    let animated = Pose::rest(&r.sk);
    for _ in 0..60 {
        r.frame(&rest, 1.0 / 60.0);
    }
    for c in 0..5 {
        for i in 0..5 {
            let j = r.sk.find(&format!("c{c}_{i}")).unwrap();
            let got = r.state.world_positions()[c * 5 + i];
            assert!(
                (got - animated.models[j].translation).length() < 1e-5,
                "{got}"
            );
        }
    }
}

#[test]
fn steady_wind_tilts_the_sheet_to_atan_wind_over_g() {
    // Wind across the sheet and gravity: at rest every chain lies along their sum, which
    // the constraints allow (a rigid turn about the pinned row).
    let wind = 4.0_f32;
    let mut r = hanging(&|s| s.wind.acceleration = Vec3::new(0.0, 0.0, wind));
    let rest = r.sk.rest().to_vec();
    for _ in 0..1200 {
        r.frame(&rest, 1.0 / 60.0);
    }
    let expected = wind.atan2(9.81);
    let pos = r.state.world_positions();
    for c in 0..5 {
        let d = pos[c * 5 + 4] - pos[c * 5];
        let angle = d.z.atan2(-d.y);
        assert!(
            (angle - expected).abs() < 0.01,
            "chain {c} at {angle}, expected {expected}"
        );
    }
}

#[test]
fn angle_limit_holds_against_strong_wind() {
    let mut r = hanging(&|s| {
        s.wind.acceleration = Vec3::new(0.0, 0.0, 30.0);
        s.limit_angle = 10.0;
    });
    let rest = r.sk.rest().to_vec();
    for _ in 0..300 {
        r.frame(&rest, 1.0 / 60.0);
    }
    // The first free segment may turn at most 10° from its animated (straight down)
    // direction; with no limit the wind would blow it to atan(30 / 9.81) ≈ 72°.
    let pos = r.state.world_positions();
    for c in 0..5 {
        let d = pos[c * 5 + 1] - pos[c * 5];
        let angle = d.angle_between(Vec3::NEG_Y).to_degrees();
        assert!(angle <= 10.0 + 0.5, "chain {c}: {angle}°");
        assert!(angle > 5.0, "the wind should lean on the limit: {angle}°");
    }
}
