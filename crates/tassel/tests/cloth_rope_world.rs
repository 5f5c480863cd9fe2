//! Bone cloths and ropes against the world (a controller `Level`), issue 20: a curtain or
//! a rope dragged across a floor never goes below it, one flung at a thin wall never
//! passes it, and the option changes nothing away from geometry.

use glam::{Quat, Vec3};
use std::sync::Arc;
use tassel::controller::Level;

mod common;
use common::line;
use tassel::dynamics::cloth::ClothSettings;
use tassel::dynamics::particles::ParticleSettings;
use tassel::dynamics::rope::RopeSettings;
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Skeleton, Transform};

const CHAINS: usize = 4;
const BONES: usize = 5;
const BONE: f32 = 0.1;

/// A bar (the anchor) at `anchor` with `CHAINS` chains of `BONES` bones hanging along
/// `dir`, 0.1 m apart along X.
fn curtain(anchor: Vec3, dir: Vec3) -> Skeleton {
    let mut names = vec!["bar".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::from_translation(anchor)];
    for k in 0..CHAINS {
        for i in 0..BONES {
            names.push(format!("c{k}_{i}"));
            if i == 0 {
                parents.push(Some(0));
                rest.push(Transform::from_translation(Vec3::new(
                    0.1 * k as f32 - 0.15,
                    0.0,
                    0.0,
                )));
            } else {
                parents.push(Some(names.len() - 2));
                rest.push(Transform::from_translation(dir * BONE));
            }
        }
    }
    Skeleton::new(names, parents, rest).unwrap()
}

fn sim(sk: &Skeleton, cloth: ClothSettings, level: &Arc<Level>) -> CharacterSim {
    let rig = RigSettings {
        cloths: vec![ClothSettings {
            name: "curtain".into(),
            chains: (0..CHAINS)
                .map(|k| [format!("c{k}_0"), format!("c{k}_{}", BONES - 1)])
                .collect(),
            virtual_bone_length: BONE,
            ..cloth
        }],
        ..Default::default()
    };
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    sim.set_level(Some(level.clone()));
    sim
}

/// World positions of the cloth's free points (the solver's own, not only the bones).
fn cloth_points(sim: &CharacterSim) -> Vec<Vec3> {
    let rig = sim.cloths();
    sim.cloth_state()
        .world_positions()
        .iter()
        .enumerate()
        .filter(|(p, _)| !rig.is_fixed(*p))
        .map(|(_, x)| *x)
        .collect()
}

/// World positions of the written bones below the bar.
fn bones(sim: &CharacterSim, comp: &Transform) -> Vec<Vec3> {
    sim.pose()
        .models
        .iter()
        .skip(1)
        .map(|m| comp.transform_point(m.translation))
        .collect()
}

#[test]
fn a_curtain_dragged_across_the_floor_never_goes_below_it() {
    // A 0.5 m curtain (4 bones below the bar's row and a virtual tip) from a bar 0.35 m up,
    // starting back and down above the floor: it falls, and its lower part must lie on
    // the floor. The character walks at 2 m/s, turns and stops.
    let floor = common::floor();
    let sk = curtain(Vec3::new(0.0, 0.35, 0.0), Vec3::new(0.0, -0.6, -0.8));
    let radius = 0.02;
    for hz in [30.0f32, 60.0, 144.0] {
        let mut s = sim(
            &sk,
            ClothSettings {
                radius,
                world_collision: true,
                ..Default::default()
            },
            &floor,
        );
        let rest = sk.rest().to_vec();
        let (mut lowest, mut lowest_bone, mut touching) = (f32::MAX, f32::MAX, 0);
        for f in 0..(4.0 * hz) as usize {
            let comp = common::drag_walk(f as f32 / hz);
            s.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / hz })
                .unwrap();
            for p in cloth_points(&s) {
                lowest = lowest.min(p.y);
                touching += (p.y < radius + 5e-3) as usize;
            }
            for b in bones(&s, &comp) {
                lowest_bone = lowest_bone.min(b.y);
            }
        }
        println!(
            "{hz} Hz: lowest cloth point {lowest:.5} m (radius {radius}), lowest written bone \
             {lowest_bone:.5} m; {touching} point-frames on the floor"
        );
        assert!(
            lowest >= radius - 1e-4,
            "{hz} Hz: a cloth point went to {lowest} m, below its radius"
        );
        // The written bones keep their lengths (rotations only): never in the floor.
        assert!(
            lowest_bone >= 0.0,
            "{hz} Hz: a bone went to {lowest_bone} m"
        );
        assert!(
            touching > 100,
            "{hz} Hz: the curtain never lay on the floor"
        );
    }
}

#[test]
fn far_from_geometry_the_option_changes_nothing() {
    let level = Arc::new(Level::new(tassel::builtin::level::bench_level(200, 7)).unwrap());
    let sk = curtain(
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, -1.0, -0.3).normalize(),
    );
    let run = |world_collision: bool| {
        let mut s = sim(
            &sk,
            ClothSettings {
                world_collision,
                ..Default::default()
            },
            &level,
        );
        let rest = sk.rest().to_vec();
        let mut out = Vec::new();
        for f in 0..240 {
            let t = f as f32 / 60.0;
            // 500 m above the level.
            let comp = Transform::from_translation(Vec3::new(0.3 * (3.0 * t).sin(), 500.0, t));
            s.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / 60.0 })
                .unwrap();
            out.extend(bones(&s, &comp));
        }
        out
    };
    assert_eq!(run(true), run(false));
    let sk = line(
        5,
        0.1,
        Vec3::new(0.3, -1.0, 0.0).normalize(),
        Vec3::new(0.0, 1.0, 0.0),
    );
    let run_rope = |world_collision: bool| {
        let mut s = rope_sim(&sk, 5, world_collision, 0.01, &level);
        let rest = sk.rest().to_vec();
        let mut out = Vec::new();
        for f in 0..240 {
            let t = f as f32 / 60.0;
            let comp = Transform::from_translation(Vec3::new(0.3 * (3.0 * t).sin(), 500.0, t));
            s.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / 60.0 })
                .unwrap();
            out.extend(bones(&s, &comp));
        }
        out
    };
    assert_eq!(run_rope(true), run_rope(false));
}

fn rope_sim(
    sk: &Skeleton,
    n: usize,
    world_collision: bool,
    radius: f32,
    level: &Arc<Level>,
) -> CharacterSim {
    let rig = RigSettings {
        ropes: vec![RopeSettings {
            name: "rope".into(),
            root: "anchor".into(),
            end: format!("b{}", n - 1),
            world_collision,
            world: ParticleSettings {
                radius,
                damping: 0.02,
                friction: 0.3,
                ..Default::default()
            },
            ..Default::default()
        }],
        ..Default::default()
    };
    let mut sim = CharacterSim::new(sk.clone(), &rig).unwrap();
    sim.set_level(Some(level.clone()));
    sim
}

#[test]
fn a_rope_dragged_across_the_floor_never_goes_below_it() {
    // A 0.6 m rope from a hand 0.4 m up, starting back and down: it falls, lies on the
    // floor and is dragged while the character walks at 2 m/s, turns and stops.
    let floor = common::floor();
    let sk = line(
        6,
        0.1,
        Vec3::new(0.0, -0.5, -0.8).normalize(),
        Vec3::new(0.0, 0.4, 0.0),
    );
    let radius = 0.015;
    for hz in [30.0f32, 60.0, 144.0] {
        let mut s = rope_sim(&sk, 6, true, radius, &floor);
        let rest = sk.rest().to_vec();
        let (mut lowest, mut lowest_bone, mut touching) = (f32::MAX, f32::MAX, 0);
        for f in 0..(4.0 * hz) as usize {
            let comp = common::drag_walk(f as f32 / hz);
            s.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / hz })
                .unwrap();
            let world = s.ropes().world(0);
            for p in world
                .positions()
                .iter()
                .chain(s.ropes().output_positions(0))
            {
                lowest = lowest.min(p.y);
                touching += (p.y < radius + 5e-3) as usize;
            }
            for b in bones(&s, &comp) {
                lowest_bone = lowest_bone.min(b.y);
            }
        }
        println!(
            "rope {hz} Hz: lowest particle or output point {lowest:.5} m (radius {radius}), \
             lowest written bone {lowest_bone:.5} m; {touching} point-frames on the floor"
        );
        assert!(
            lowest >= radius - 1e-4,
            "{hz} Hz: a rope point went to {lowest} m"
        );
        assert!(
            lowest_bone >= 0.0,
            "{hz} Hz: a bone went to {lowest_bone} m"
        );
        assert!(touching > 100, "{hz} Hz: the rope never lay on the floor");
    }
}

/// The demo run (the controller's level, the built-in rig): the skirt and the charm touch
/// the wall the character slides along, and never go into it; without world collision the
/// charm swings 11 cm into it.
#[test]
fn in_the_demo_the_skirt_and_the_charm_touch_the_wall_and_never_enter_it() {
    use tassel::builtin::{self, level::LevelRun, DemoScript};
    let c = builtin::character();
    assert!(c.rig.cloths[0].world_collision && c.rig.ropes[0].world_collision);
    let depth =
        |level: &Level, p: Vec3, r: f32| level.capsule_penetration(r, 0.0, p, Quat::IDENTITY);
    for world_collision in [true, false] {
        let mut rig = c.rig.clone();
        rig.cloths[0].world_collision = world_collision;
        rig.ropes[0].world_collision = world_collision;
        let mut sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
        let mut run = LevelRun::new().unwrap();
        sim.set_level(Some(run.level.clone()));
        let mut animator = DemoScript.animator(&c);
        let mut locals = c.skeleton.rest().to_vec();
        let fps = 60.0;
        let (skirt_r, charm_r) = (rig.cloths[0].radius, rig.ropes[0].world.radius);
        let (mut deepest, mut skirt_touches, mut charm_touches) = (0.0f32, 0, 0);
        for f in 0..=(LevelRun::DURATION * fps).round() as usize {
            let dt = if f == 0 { 0.0 } else { 1.0 / fps };
            let m = run
                .frame(&c, &mut animator, f as f32 / fps, dt, &mut locals)
                .unwrap();
            // The door and the platform move: the solvers see this frame's level.
            sim.set_level(Some(run.level.clone()));
            sim.frame(&locals, m.component, dt).unwrap();
            // The points the solvers move (not the skirt's waist ring nor the charm's
            // root: they follow the animation, and the animated left hand goes 35 mm into
            // the wall), off the floor: the wall, the stairs' and the ramp's sides.
            let cloths = sim.cloths();
            for (i, &p) in sim.cloth_state().world_positions().iter().enumerate() {
                if p.y > 0.1 && !cloths.is_fixed(i) {
                    deepest = deepest.max(depth(&run.level, p, skirt_r));
                    skirt_touches += (depth(&run.level, p, skirt_r + 2e-3) > 0.0) as usize;
                }
            }
            for &p in &sim.ropes().output_positions(0)[1..] {
                if p.y > 0.1 {
                    deepest = deepest.max(depth(&run.level, p, charm_r));
                    charm_touches += (depth(&run.level, p, charm_r + 2e-3) > 0.0) as usize;
                }
            }
        }
        println!(
            "world_collision {world_collision}: deepest skirt or charm point {:.1} mm into its \
             radius; point-frames touching: skirt {skirt_touches}, charm {charm_touches}",
            deepest * 1e3
        );
        if world_collision {
            assert!(deepest <= 1e-4, "{deepest} m into the level");
            assert!(
                skirt_touches > 0 && charm_touches > 0,
                "no contact with the wall"
            );
        } else {
            assert!(
                deepest > 0.05,
                "the charm should swing into the wall without it"
            );
        }
    }
}

/// A solver flung at a thin wall: the character runs at 10 m/s for 0.1 s and stops 0.2 m
/// before a 5 cm wall, the hanging cloth or rope (left behind by the start) swings ahead
/// with the run's momentum. With world collision no point (`points`, world space) ever
/// gets nearer the wall than its radius, and it does reach the wall; without it, the
/// points swing through (so the scene tests something).
fn flung_at_a_thin_wall(
    what: &str,
    radius: f32,
    make: impl Fn(bool, &Arc<Level>) -> CharacterSim,
    points: impl Fn(&CharacterSim, &Transform) -> Vec<f32>,
) {
    let wall_near = 1.2;
    let wall = common::thin_wall(wall_near);
    let mut passed_without = false;
    for world_collision in [true, false] {
        for hz in [30.0f32, 60.0, 144.0] {
            let mut s = make(world_collision, &wall);
            let rest = s.skeleton().rest().to_vec();
            let mut farthest = f32::MIN;
            for f in 0..(1.5 * hz) as usize {
                let comp = common::flung(f as f32 / hz);
                s.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / hz })
                    .unwrap();
                farthest = points(&s, &comp).into_iter().fold(farthest, f32::max);
            }
            if world_collision {
                println!("{what} {hz} Hz: farthest point {farthest:.4} m (wall at {wall_near} m)");
                assert!(
                    farthest <= wall_near - radius + 1e-4,
                    "{what} {hz} Hz: a point reached {farthest} m, the wall is at {wall_near}"
                );
                assert!(
                    farthest > wall_near - 0.05,
                    "{what} {hz} Hz: never reached the wall"
                );
            } else {
                passed_without |= farthest > wall_near + 0.05;
            }
        }
    }
    assert!(
        passed_without,
        "without world collision the {what} should swing through the wall"
    );
}

#[test]
fn a_cloth_flung_at_a_thin_wall_never_passes_it() {
    // The curtain hangs from a bar 1 m up.
    let sk = curtain(Vec3::new(0.0, 1.0, 0.0), Vec3::NEG_Y);
    let radius = 0.01;
    flung_at_a_thin_wall(
        "cloth",
        radius,
        |world_collision, wall| {
            let cloth = ClothSettings {
                radius,
                world_collision,
                resistance: 0.0,
                ..Default::default()
            };
            sim(&sk, cloth, wall)
        },
        |s, _| cloth_points(s).iter().map(|p| p.z).collect(),
    );
}

#[test]
fn a_rope_flung_at_a_thin_wall_never_passes_it() {
    // A 0.5 m rope hangs from a hand 1 m up; its written bones count too.
    let sk = line(5, 0.1, Vec3::NEG_Y, Vec3::new(0.0, 1.0, 0.0));
    let radius = 0.01;
    flung_at_a_thin_wall(
        "rope",
        radius,
        |world_collision, wall| rope_sim(&sk, 5, world_collision, radius, wall),
        |s, comp| {
            let world = s.ropes().world(0);
            let particles = world
                .positions()
                .iter()
                .chain(s.ropes().output_positions(0));
            particles
                .map(|p| p.z)
                .chain(bones(s, comp).iter().map(|b| b.z - radius))
                .collect()
        },
    );
}
