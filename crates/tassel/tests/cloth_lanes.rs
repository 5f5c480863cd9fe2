//! A bone cloth's contact tests in SIMD lanes (`crowd/cloth_lanes.rs`) against the scalar
//! cloth job (the readable reference): the same bits, frame after frame, where the cloth
//! really meets its colliders: the built-in skirt through the demo, and a sheet that a
//! ball, a bar, a box, a floor and a keep-inside limit push through every contact test
//! (points, segments, both surface modes), with hitches, a pause and a jump; and the
//! angle limit, whose chains run side by side in lanes too.

mod common;

use glam::{Quat, Vec3};
use tassel::builtin::{self, DemoScript};
use tassel::collide::Shape;
use tassel::crowd::SimdUse;
use tassel::dynamics::cloth::{ClothSettings, SurfaceCollision};
use tassel::dynamics::{ColliderSettings, Curve, RigSettings};
use tassel::{CharacterSim, Skeleton, SkeletonBuilder, Transform};

/// The ways of running the contact tests: scalar (the reference), portable lanes, AVX2
/// lanes at most and the widest lanes where the CPU has them, and one switched between
/// scalar and lanes every 37 frames.
const WAYS: [SimdUse; 5] = [
    SimdUse::Scalar,
    SimdUse::Portable,
    SimdUse::Avx2,
    SimdUse::Auto,
    SimdUse::Scalar,
];

/// One character per way; `frame(f, locals)` gives frame `f`'s character transform and
/// time step and fills the animated pose. After every frame, every local and model
/// transform and every cloth point (world and model space) must be the scalar one's bits.
/// Returns the scalar character's cloth points of every frame (world space).
fn assert_lanes_match(
    sk: &Skeleton,
    rig: &RigSettings,
    frames: usize,
    mut frame: impl FnMut(usize, &mut [Transform]) -> (Transform, f32),
) -> Vec<Vec<Vec3>> {
    let mut sims: Vec<CharacterSim> = WAYS
        .iter()
        .map(|&simd| {
            let mut sim = CharacterSim::new(sk.clone(), rig).unwrap();
            sim.set_simd(simd);
            sim
        })
        .collect();
    let mut locals = sk.rest().to_vec();
    let mut history = Vec::new();
    for f in 0..frames {
        if f % 37 == 0 {
            let simd = if (f / 37) % 2 == 0 {
                SimdUse::Scalar
            } else {
                SimdUse::Auto
            };
            sims[4].set_simd(simd);
        }
        let (component, dt) = frame(f, &mut locals);
        let poses: Vec<_> = sims
            .iter_mut()
            .map(|sim| sim.frame(&locals, component, dt).unwrap().clone())
            .collect();
        for (k, pose) in poses.iter().enumerate().skip(1) {
            let what = format!("frame {f}, way {k} ({:?})", WAYS[k]);
            common::assert_pose_bits(sk, &what, pose, &poses[0]);
            let (a, b) = (sims[k].cloth_state(), sims[0].cloth_state());
            let bits = |v: &[Vec3]| -> Vec<[u32; 3]> {
                v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
            };
            assert_eq!(
                bits(a.world_positions()),
                bits(b.world_positions()),
                "frame {f}, way {k} ({:?}): cloth points",
                WAYS[k]
            );
            assert_eq!(bits(a.output_positions()), bits(b.output_positions()));
            assert_eq!(a.reset_count(), b.reset_count());
        }
        history.push(sims[0].cloth_state().world_positions().to_vec());
    }
    history
}

/// The largest distance between the same point in two runs.
fn largest_gap(a: &[Vec<Vec3>], b: &[Vec<Vec3>]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| p.distance(*q)))
        .fold(0.0, f32::max)
}

/// The built-in character through the demo (walk, run, turns, a jump; the skirt brushes
/// the legs): the lanes give the scalar bits. The legs really act on the skirt: without
/// its colliders it ends up elsewhere.
#[test]
fn the_skirt_through_the_demo_gives_the_scalar_bits_in_lanes() {
    let c = builtin::character();
    let sk = &c.skeleton;
    let frames = (DemoScript::DURATION * 60.0).round() as usize;
    let run = |rig: &RigSettings| {
        let script = DemoScript;
        let mut animator = script.animator(&c);
        assert_lanes_match(sk, rig, frames, |f, locals| {
            let dt = 1.0 / 60.0;
            let m = script.at(f as f32 * dt);
            let step = if f == 0 { 0.0 } else { dt };
            script.pose(&c, &mut animator, &m, step, locals).unwrap();
            (m.component, step)
        })
    };
    // The rig with everything (chains, springs, ropes beside the cloth), and the cloth
    // alone without colliders (a cloth with an empty list would take every collider).
    let with = run(&c.rig);
    let mut bare = RigSettings {
        cloths: c.rig.cloths.clone(),
        ..Default::default()
    };
    bare.cloths[0].colliders.clear();
    let without = run(&bare);
    let gap = largest_gap(&with, &without);
    assert!(
        gap > 0.01,
        "the legs moved the skirt by {gap} m at most: the contact tests were not tested"
    );
}

/// A sheet of 6 chains of 5 bones hanging from a bar, and a mover bone that carries the
/// colliders: a ball and a bar sweeping through the sheet, a box, a floor and a
/// keep-inside limit.
fn sheet() -> (Skeleton, Vec<[String; 2]>) {
    let mut b = SkeletonBuilder::new();
    let root = b.add("root", None, Transform::IDENTITY);
    b.add("mover", Some(root), Transform::IDENTITY);
    let mut pairs = Vec::new();
    for c in 0..6 {
        let mut p = b.add(
            format!("c{c}_0"),
            Some(root),
            Transform::from_translation(Vec3::new(c as f32 * 0.12 - 0.3, 1.0, 0.0)),
        );
        for i in 1..5 {
            p = b.add(
                format!("c{c}_{i}"),
                Some(p),
                Transform::from_translation(Vec3::new(0.0, -0.12, 0.0)),
            );
        }
        pairs.push([format!("c{c}_0"), format!("c{c}_4")]);
    }
    (b.build().unwrap().0, pairs)
}

fn collider(name: &str, offset: Vec3, rotation: Quat, shape: Shape) -> ColliderSettings {
    ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: name.into(),
        bone: if name == "floor" || name == "limit" {
            "root"
        } else {
            "mover"
        }
        .into(),
        offset,
        rotation,
        shape,
    }
}

/// The sheet's rig: every collider shape, a radius that grows down the chains, a wider
/// point ring with `fixed_point_index` 1 on the first variant.
fn sheet_rig(pairs: Vec<[String; 2]>, mode: SurfaceCollision, segments: bool) -> RigSettings {
    RigSettings {
        cloths: vec![ClothSettings {
            name: "sheet".into(),
            chains: pairs,
            virtual_bone_length: 0.06,
            radius: 0.02,
            curves: tassel::dynamics::cloth::PointCurves {
                radius: Curve::new(vec![[0.0, 0.5], [1.0, 1.5]]),
                ..Default::default()
            },
            fixed_point_index: u32::from(mode == SurfaceCollision::Push),
            segment_collision: segments,
            surface_collision: mode,
            colliders: ["ball", "bar", "box", "floor", "limit"]
                .map(String::from)
                .to_vec(),
            ..Default::default()
        }],
        colliders: vec![
            collider(
                "ball",
                Vec3::new(0.0, 0.7, 0.0),
                Quat::IDENTITY,
                Shape::Sphere {
                    radius: 0.07,
                    inside: false,
                },
            ),
            collider(
                "bar",
                Vec3::new(0.1, 0.5, 0.0),
                Quat::from_rotation_z(1.3),
                Shape::Capsule {
                    radius: 0.04,
                    length: 0.5,
                },
            ),
            collider(
                "box",
                Vec3::new(-0.2, 0.55, 0.0),
                Quat::from_rotation_y(0.4),
                Shape::Box {
                    half_extents: Vec3::new(0.05, 0.04, 0.06),
                },
            ),
            collider(
                "floor",
                Vec3::new(0.0, 0.42, 0.0),
                Quat::from_rotation_x(0.15),
                Shape::Plane,
            ),
            collider(
                "limit",
                Vec3::new(0.0, 0.8, 0.0),
                Quat::IDENTITY,
                Shape::Sphere {
                    radius: 0.62,
                    inside: true,
                },
            ),
        ],
        ..Default::default()
    }
}

/// The sheet with each surface mode and without segments: the colliders sweep back and
/// forth through it (the mover swings along Z by ±0.4 m), the character sways, hitches,
/// pauses and jumps 10 m (a reset) at frame 450.
#[test]
fn a_sheet_pushed_by_every_shape_gives_the_scalar_bits_in_lanes() {
    let (sk, pairs) = sheet();
    let mover = sk.find("mover").unwrap();
    // The last item: the angle limit (degrees, 0 = off).
    let cases = [
        (SurfaceCollision::PushPull, true, 0.0),
        (SurfaceCollision::Push, true, 25.0),
        (SurfaceCollision::Off, true, 0.0),
        (SurfaceCollision::PushPull, false, 12.0),
    ];
    for (mode, segments, limit_angle) in cases {
        let run = |rig: &RigSettings| {
            assert_lanes_match(&sk, rig, 600, |f, locals| {
                let t = f as f32 / 60.0;
                locals.copy_from_slice(sk.rest());
                locals[mover].translation = Vec3::new(
                    0.15 * (1.3 * t).sin(),
                    0.1 * (0.7 * t).sin(),
                    0.4 * (2.1 * t).sin(),
                );
                locals[mover].rotation = Quat::from_rotation_y(0.5 * t);
                let jump = if f >= 450 { 10.0 } else { 0.0 };
                let component = Transform::from_translation_rotation(
                    Vec3::new(0.2 * (1.5 * t).sin() + jump, 0.0, 0.3 * t),
                    Quat::from_rotation_y(0.3 * (0.9 * t).sin()),
                );
                (component, common::dt_with_hitches(f))
            })
        };
        let mut rig = sheet_rig(pairs.clone(), mode, segments);
        rig.cloths[0].limit_angle = limit_angle;
        let with = run(&rig);
        if limit_angle > 0.0 {
            // The limit really turned segments back.
            let mut free = rig.clone();
            free.cloths[0].limit_angle = 0.0;
            let gap = largest_gap(&with, &run(&free));
            assert!(
                gap > 0.01,
                "{mode:?}: the angle limit moved the sheet by {gap} m at most"
            );
        }
        let mut bare = rig.clone();
        bare.cloths[0].colliders.clear();
        bare.colliders.clear();
        let without = run(&bare);
        let gap = largest_gap(&with[..440], &without[..440]);
        assert!(
            gap > 0.05,
            "{mode:?}, segments {segments}: the colliders moved the sheet by {gap} m at most"
        );
    }
}
