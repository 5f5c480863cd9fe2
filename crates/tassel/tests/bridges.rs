//! Bridge points on bone constraints (issue 62 item 2; KawaiiPhysics 1.21's
//! `BoneConstraintSubdivisionCount`, `BoneConstraintSubdivisionFeedbackScale`,
//! `bExcludeFromSubdivision`, read at its `20260624-v1.21.0` tag:
//! `InsertBridgeDummiesForConstraints` and the bridge passes of `SimulateOnce`).
//!
//! The skirt of `examples/rigs/skirt-chains.toml` (eight chains joined at every level by
//! bone constraints) on the built-in character, its left thigh kicked forward and back
//! (±1.3 rad at 1 Hz) so that the thigh's capsule swings through the skirt's front. Each
//! frame, for each pair of neighbouring chains and each pair of levels, the quad between
//! their two segments: does the capsule's axis pass through it while no point of those
//! segments, and no bridge point on their constraints, touches the capsule (within 1 mm)?
//! Counted without bridges and with 3 a constraint, at 60 and 144 Hz.

use glam::{Quat, Vec3};
use tassel::builtin;
use tassel::collide::Shape;
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Transform};

fn skirt_rig(bridges: u32) -> RigSettings {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../examples/rigs/skirt-chains.toml"
    );
    let mut rig = RigSettings::from_toml_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    rig.bone_constraint_subdivision_count = bridges;
    // A slim leg (3 cm): narrower than the gaps between the skirt's lower columns.
    for c in &mut rig.colliders {
        if let Shape::Capsule { radius, .. } = &mut c.shape {
            *radius = 0.03;
        }
    }
    rig
}

/// Whether segment `p0`–`p1` passes through triangle `a b c` (Möller–Trumbore).
fn crosses(p0: Vec3, p1: Vec3, a: Vec3, b: Vec3, c: Vec3) -> bool {
    let d = p1 - p0;
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(e2);
    let det = e1.dot(h);
    if det.abs() < 1e-12 {
        return false;
    }
    let f = 1.0 / det;
    let s = p0 - a;
    let u = f * s.dot(h);
    let q = s.cross(e1);
    let v = f * d.dot(q);
    let t = f * e2.dot(q);
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && (0.0..=1.0).contains(&t)
}

/// The distance from `x` to segment `a`–`b`.
fn to_segment(x: Vec3, a: Vec3, b: Vec3) -> f32 {
    let s = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
    x.distance(a + (b - a) * s)
}

/// Frames in which the thigh passed between two neighbouring chains untouched, and the
/// frames in which it passed between them at all.
fn run(bridges: u32, hz: f32) -> (usize, usize) {
    let c = builtin::character();
    let rig = skirt_rig(bridges);
    let mut sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
    let sk = c.skeleton.clone();
    let chains = sim.rig().chains().clone();
    assert_eq!(chains.bridge_count() > 0, bridges > 0);
    let thigh = sk.find("thigh_l").unwrap();
    let collider = rig
        .colliders
        .iter()
        .position(|c| c.name == "thigh_l")
        .unwrap();
    let Shape::Capsule { radius, length } = rig.colliders[collider].shape else {
        panic!("the thigh is a capsule");
    };
    // Per column, its points from the top down (the bones, then the tip).
    let point_of = |j: usize| (0..chains.point_count()).find(|&p| chains.point(p).joint == Some(j));
    let columns: Vec<Vec<usize>> = (0..8)
        .map(|k| {
            let mut col: Vec<usize> = (0..4)
                .map(|i| point_of(sk.find(&format!("skirt_{k}_{i}")).unwrap()).unwrap())
                .collect();
            let last = *col.last().unwrap();
            if let Some(tip) = (0..chains.point_count())
                .find(|&p| chains.point(p).joint.is_none() && chains.point(p).parent == Some(last))
            {
                col.push(tip);
            }
            col
        })
        .collect();
    let rest = sk.rest().to_vec();
    let (mut untouched, mut between) = (0, 0);
    for f in 0..=(4.0 * hz) as usize {
        let t = f as f32 / hz;
        let mut locals = rest.clone();
        locals[thigh].rotation =
            rest[thigh].rotation * Quat::from_rotation_x(-1.3 * (std::f32::consts::TAU * t).sin());
        sim.frame(
            &locals,
            Transform::IDENTITY,
            if f == 0 { 0.0 } else { 1.0 / hz },
        )
        .unwrap();
        let state = sim.chain_state();
        let out = state.output_positions();
        let placed = state.placed_colliders()[collider];
        let axis = placed.transform.rotation * Vec3::Y * (0.5 * length);
        let (p0, p1) = (
            placed.transform.translation - axis,
            placed.transform.translation + axis,
        );
        let touches = |x: Vec3, r: f32| to_segment(x, p0, p1) < radius + r + 1e-3;
        let (mut any_untouched, mut any_between) = (false, false);
        for k in 0..8 {
            let (ca, cb) = (&columns[k], &columns[(k + 1) % 8]);
            for i in 0..ca.len().min(cb.len()) - 1 {
                let (a0, a1, b0, b1) = (ca[i], ca[i + 1], cb[i], cb[i + 1]);
                let q = [out[a0], out[a1], out[b1], out[b0]];
                if !(crosses(p0, p1, q[0], q[1], q[2]) || crosses(p0, p1, q[0], q[2], q[3])) {
                    continue;
                }
                any_between = true;
                let mut touched = [a0, a1, b0, b1]
                    .iter()
                    .any(|&p| touches(out[p], chains.point_radius(p)));
                for (n, x) in state.bridge_positions().iter().enumerate() {
                    let (ea, eb, _, r) = chains.bridge(n).unwrap();
                    let on_edge = [(a0, b0), (a1, b1)]
                        .iter()
                        .any(|&(u, v)| (ea, eb) == (u, v) || (ea, eb) == (v, u));
                    touched |= on_edge && touches(*x, r);
                }
                any_untouched |= !touched;
            }
        }
        untouched += usize::from(any_untouched);
        between += usize::from(any_between);
    }
    (untouched, between)
}

#[test]
fn bridges_stop_a_leg_passing_between_skirt_chains() {
    for hz in [60.0, 144.0] {
        let (without, between) = run(0, hz);
        let (with, between_with) = run(3, hz);
        println!(
            "{hz} Hz: the thigh passed between two chains untouched in {without} frames \
             ({between} between them at all) without bridges; {with} ({between_with}) with \
             3 bridge points a constraint"
        );
        assert!(
            without > 0,
            "{hz} Hz: the thigh never slipped between the chains"
        );
        assert_eq!(with, 0, "{hz} Hz: with bridges the thigh slipped through");
    }
}

/// The keys: read and written back; refused out of range by name; how many bridge points
/// a rig gets, counted here from the rest pose: `count` on each constraint (the dummy
/// tips' included) unless excluded or its two points' spheres overlap at rest; and a
/// feedback scale of 0 leaves the chains exactly as without bridges (the points collide,
/// nothing reaches the chains).
#[test]
fn bridge_keys_counts_and_feedback() {
    let text = "bone_constraint_subdivision_count = 2\nbone_constraint_subdivision_feedback_scale = 0.5\n\
                [[chain]]\nname = \"a\"\nroot = \"skirt_0_0\"\n[[chain]]\nname = \"b\"\nroot = \"skirt_1_0\"\n\
                [[bone_constraint]]\nbone1 = \"skirt_0_1\"\nbone2 = \"skirt_1_1\"\n\
                [[bone_constraint]]\nbone1 = \"skirt_0_2\"\nbone2 = \"skirt_1_2\"\nexclude_from_subdivision = true\n";
    let rig = RigSettings::from_toml_str(text).unwrap();
    assert_eq!(rig.bone_constraint_subdivision_count, 2);
    assert_eq!(rig.bone_constraint_subdivision_feedback_scale, 0.5);
    assert!(rig.bone_constraints[1].exclude_from_subdivision);
    let back = rig.to_toml_string().unwrap();
    assert_eq!(RigSettings::from_toml_str(&back).unwrap(), rig);
    assert!(!RigSettings::default()
        .to_toml_string()
        .unwrap()
        .contains("subdivision"));
    for (key, bad) in [
        (
            "bone_constraint_subdivision_count = 2",
            "bone_constraint_subdivision_count = 11",
        ),
        (
            "bone_constraint_subdivision_feedback_scale = 0.5",
            "bone_constraint_subdivision_feedback_scale = 2.5",
        ),
        (
            "bone_constraint_subdivision_feedback_scale = 0.5",
            "bone_constraint_subdivision_feedback_scale = -0.1",
        ),
        (
            "bone_constraint_subdivision_feedback_scale = 0.5",
            "bone_constraint_subdivision_feedback_scale = nan",
        ),
    ] {
        let e = RigSettings::from_toml_str(&text.replace(key, bad))
            .unwrap_err()
            .to_string();
        let name = bad.split(' ').next().unwrap();
        assert!(e.contains(name), "{bad}: {e}");
    }
    // Counts: the excluded pair has none; the other, 2.
    let c = builtin::character();
    let sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
    assert_eq!(sim.rig().chains().bridge_count(), 2);
    // The skirt file: neighbours joined at three levels and at their tips, 8 pairs.
    let skirt = skirt_rig(3);
    let sim = CharacterSim::new(c.skeleton.clone(), &skirt).unwrap();
    let chains = sim.rig().chains();
    let mut expected = 0;
    let models = tassel::Pose::rest(&c.skeleton).models;
    let point_at = |p: usize| -> Vec3 {
        match chains.point(p).joint {
            Some(j) => models[j].translation,
            None => Vec3::NAN,
        }
    };
    for i in 0..chains.bridge_count() {
        let (a, b, alpha, r) = chains.bridge(i).unwrap();
        assert!((0.0..1.0).contains(&alpha) && alpha > 0.0);
        assert!((r - 0.5 * (chains.point_radius(a) + chains.point_radius(b))).abs() < 1e-7);
        let d = point_at(a).distance(point_at(b));
        // (A dummy tip has no joint: its place is the chain's rule, not the skeleton's.)
        if d.is_finite() {
            assert!(d > chains.point_radius(a) + chains.point_radius(b), "{d}");
        }
        expected += 1;
    }
    assert_eq!(expected % 3, 0, "three a constraint");
    assert!(
        expected >= 3 * 8 * 3,
        "{expected} bridge points on the skirt"
    );

    // Feedback 0: the chains as without bridges, bit for bit.
    let outputs = |rig: &RigSettings| {
        let mut sim = CharacterSim::new(c.skeleton.clone(), rig).unwrap();
        let rest = c.skeleton.rest().to_vec();
        let thigh = c.skeleton.find("thigh_l").unwrap();
        let mut all = Vec::new();
        for f in 0..=240 {
            let mut locals = rest.clone();
            locals[thigh].rotation = rest[thigh].rotation
                * Quat::from_rotation_x(-1.3 * (std::f32::consts::TAU * f as f32 / 60.0).sin());
            sim.frame(
                &locals,
                Transform::IDENTITY,
                if f == 0 { 0.0 } else { 1.0 / 60.0 },
            )
            .unwrap();
            all.extend(
                sim.chain_state()
                    .output_positions()
                    .iter()
                    .map(|v| v.to_array().map(f32::to_bits)),
            );
        }
        all
    };
    let mut silent = skirt_rig(3);
    silent.bone_constraint_subdivision_feedback_scale = 0.0;
    assert_eq!(outputs(&silent), outputs(&skirt_rig(0)));
    assert_ne!(
        outputs(&skirt_rig(3)),
        outputs(&skirt_rig(0)),
        "the feedback moves the skirt"
    );
}

/// A state made for the same skirt with another number of bridge points (the same
/// points, chains, colliders and constraints) is refused by name, not read out of bounds.
#[test]
fn a_state_of_a_rig_with_other_bridges_is_refused() {
    use tassel::dynamics::chain::{ChainJob, ChainRig, ChainState};
    let c = builtin::character();
    let sk = &c.skeleton;
    let with = ChainRig::new(sk, &skirt_rig(3)).unwrap();
    let without = ChainRig::new(sk, &skirt_rig(0)).unwrap();
    assert_eq!(with.point_count(), without.point_count());
    for (rig, other) in [(&with, &without), (&without, &with)] {
        let mut wrong = ChainState::new(other);
        let mut locals = sk.rest().to_vec();
        let mut models = tassel::Pose::rest(sk).models;
        let err = ChainJob {
            skeleton: sk,
            rig,
            state: &mut wrong,
            component: Transform::IDENTITY,
            dt: 1.0 / 60.0,
            locals: &mut locals,
            models: &mut models,
            level: None,
        }
        .run()
        .unwrap_err();
        assert!(err.to_string().contains("another chain rig"), "{err}");
    }
}

/// KawaiiPhysics 1.21's constraints across subdivided columns (`CollectInterBoneDummies`):
/// with `bone_subdivision_count = 2` on the skirt's chains, each bone constraint whose two
/// bones have points between bones below them joins those points pair by pair, at the
/// same depth below the two bones (and the tips behind split last segments as the last
/// pair); the pairs are the only constraints between points between bones; and they hold
/// the columns' middles apart: with the leg kicked through the skirt the pairs' distances
/// stray from their rest less with them than without (`auto_add_child_dummy_bone_constraint
/// = false`).
#[test]
fn split_columns_are_joined_between_bones() {
    let c = builtin::character();
    let split = |auto: bool| {
        let mut rig = skirt_rig(0);
        rig.auto_add_child_dummy_bone_constraint = auto;
        for ch in &mut rig.chains {
            ch.bone_subdivision_count = 2;
        }
        rig
    };
    let sim = CharacterSim::new(c.skeleton.clone(), &split(true)).unwrap();
    let chains = sim.rig().chains().clone();
    // A point between bones: no joint, and a child (a tip has none).
    let has_child = |p: usize| (0..chains.point_count()).any(|q| chains.point(q).parent == Some(p));
    let between = |p: usize| chains.point(p).joint.is_none() && has_child(p);
    // Its depth below its bone, and the bone.
    let below = |mut p: usize| {
        let mut depth = 0;
        while chains.point(p).joint.is_none() {
            p = chains.point(p).parent.unwrap();
            depth += 1;
        }
        (p, depth)
    };
    let list: Vec<(usize, usize, f32)> = (0..chains.bone_constraint_count())
        .map(|i| chains.bone_constraint(i).unwrap())
        .collect();
    let bones: Vec<(usize, usize)> = list
        .iter()
        .filter(|(a, b, _)| chains.point(*a).joint.is_some() && chains.point(*b).joint.is_some())
        .map(|&(a, b, _)| (a, b))
        .collect();
    let pairs: Vec<(usize, usize, f32)> = list
        .iter()
        .copied()
        .filter(|&(a, b, _)| between(a) || between(b))
        .collect();
    for &(a, b, rest) in &pairs {
        assert!(
            between(a) && between(b),
            "{a}–{b}: a pair joins two points between bones"
        );
        let ((ra, da), (rb, db)) = (below(a), below(b));
        assert_eq!(da, db, "{a}–{b}: at the same depth");
        assert!(
            bones.contains(&(ra, rb)),
            "{a}–{b}: below a constrained pair of bones"
        );
        assert!(rest > 0.0);
    }
    // Two points on each split segment: two pairs per constrained pair of bones with a
    // segment below each.
    let with_below = bones
        .iter()
        .filter(|&&(a, b)| {
            let split_below = |p: usize| {
                (0..chains.point_count()).any(|q| chains.point(q).parent == Some(p) && between(q))
            };
            split_below(a) && split_below(b)
        })
        .count();
    assert!(with_below > 0);
    assert_eq!(pairs.len(), 2 * with_below);

    // Behaviour: the kicked skirt, the pairs' stray from rest with and without.
    let stray = |auto: bool| {
        let mut sim = CharacterSim::new(c.skeleton.clone(), &split(auto)).unwrap();
        let sk = c.skeleton.clone();
        let thigh = sk.find("thigh_l").unwrap();
        let rest = sk.rest().to_vec();
        let (mut sum, mut n) = (0.0f64, 0usize);
        for f in 0..=240 {
            let t = f as f32 / 60.0;
            let mut locals = rest.clone();
            locals[thigh].rotation = rest[thigh].rotation
                * Quat::from_rotation_x(-1.3 * (std::f32::consts::TAU * t).sin());
            let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
            sim.frame(&locals, Transform::IDENTITY, dt).unwrap();
            let out = sim.chain_state().output_positions();
            for &(a, b, r) in &pairs {
                let d = (out[a].distance(out[b]) - r) as f64;
                sum += d * d;
                n += 1;
            }
        }
        (sum / n as f64).sqrt()
    };
    let (with, without) = (stray(true), stray(false));
    println!(
        "{} pairs across split columns: their distances stray {:.2} mm RMS from rest with \
         them, {:.2} mm without",
        pairs.len(),
        1e3 * with,
        1e3 * without
    );
    assert!(with < 0.8 * without, "{with} vs {without}");
}
