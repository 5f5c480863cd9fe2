//! Colliders shared between characters (issue 62 item 4; KawaiiPhysics' shared collision on
//! its master branch after 1.21): one character's `[[collider_group]]` placed in the world,
//! handed to another whose chains `use_shared_collision`. A prop swung fast through a
//! hanging chain never has a point inside it at 30, 60, 144 and 200 Hz (and does without
//! the shared colliders); the keys are read, written and refused by name; bad shared
//! colliders and unknown groups are refused; such rigs step per character in crowds.

use glam::{Quat, Vec3};
use tassel::collide::{PlacedCollider, Shape};
use tassel::dynamics::chain::{ClassicGravity, TimeMode};
use tassel::dynamics::{ColliderGroupSettings, ColliderSettings, RigSettings};
use tassel::{CharacterSim, Skeleton, Transform};

mod common;
use common::hair::{skeleton, BONES};

const PROP_R: f32 = 0.06;
const POINT_R: f32 = 0.02;

/// A one-bone "hand" holding a sphere, and its group `prop`.
fn holder() -> (Skeleton, RigSettings) {
    let sk = Skeleton::new(vec!["hand".into()], vec![None], vec![Transform::IDENTITY]).unwrap();
    let rig = RigSettings {
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "ball".into(),
            bone: "hand".into(),
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            shape: Shape::Sphere {
                radius: PROP_R,
                inside: false,
            },
        }],
        collider_groups: vec![ColliderGroupSettings {
            name: "prop".into(),
            colliders: vec!["ball".into()],
        }],
        ..Default::default()
    };
    (sk, rig)
}

/// The hair chain with a radius, in `mode`, using shared colliders or not.
fn cape(mode: TimeMode, shared: bool) -> RigSettings {
    let mut chain = common::kawaii::hair_chain(mode, ClassicGravity::PerFrame);
    chain.radius = POINT_R;
    chain.use_shared_collision = shared;
    RigSettings {
        chains: vec![chain],
        ..Default::default()
    }
}

/// Where the prop is at `t`: swung across the chain at up to π m/s.
fn prop_at(t: f32) -> Transform {
    Transform::from_translation(Vec3::new(
        0.5 * (std::f32::consts::TAU * t).sin(),
        1.42,
        -0.16,
    ))
}

/// Frames at `hz` for 2 s, the prop's holder stepped first, its colliders handed to the
/// chain's character (when `hand` is true) before its frame. Returns the deepest any chain
/// point went into the prop (metres; ≤ 0: none) and in how many frames one was inside.
fn swing(mode: TimeMode, hz: u32, shared: bool, hand: bool) -> (f32, usize) {
    let (hsk, hrig) = holder();
    let mut holder = CharacterSim::new(hsk.clone(), &hrig).unwrap();
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &cape(mode, shared)).unwrap();
    let rest = sk.rest().to_vec();
    let mut colliders = Vec::new();
    let (mut deepest, mut frames) = (f32::NEG_INFINITY, 0);
    // The character sways a little too (its own transform is not the world's).
    for f in 0..=2 * hz {
        let t = f as f32 / hz as f32;
        let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
        holder.frame(hsk.rest(), prop_at(t), dt).unwrap();
        if hand {
            holder
                .shared_colliders_into(Some("prop"), &mut colliders)
                .unwrap();
            sim.set_shared_colliders(&colliders).unwrap();
        }
        let comp = Transform::from_translation_rotation(
            Vec3::new(0.0, 0.0, 0.05 * t.sin()),
            Quat::from_rotation_y(0.2 * t.sin()),
        );
        sim.frame(&rest, comp, dt).unwrap();
        let centre = prop_at(t).translation;
        let mut inside = false;
        for j in 1..=BONES {
            let x = comp.transform_point(sim.pose().models[j].translation);
            let depth = PROP_R + POINT_R - x.distance(centre);
            deepest = deepest.max(depth);
            inside |= depth > 1e-4;
        }
        frames += usize::from(inside);
    }
    (deepest, frames)
}

#[test]
fn a_prop_swung_through_a_chain_never_has_a_point_inside() {
    for mode in [TimeMode::Fixed, TimeMode::Classic, TimeMode::Kawaii] {
        for hz in [30, 60, 144, 200] {
            let (deep_off, frames_off) = swing(mode, hz, false, true);
            let (deep_unset, _) = swing(mode, hz, true, false);
            let (deep, frames) = swing(mode, hz, true, true);
            println!(
                "{mode:?} {hz} Hz: a prop at up to 3.1 m/s through the chain: deepest {:.1} mm \
                 in {frames_off} frames without shared collision, {:.3} mm in {frames} frames \
                 with",
                1e3 * deep_off,
                1e3 * deep.max(0.0)
            );
            assert!(
                frames_off > 0 && deep_off > 0.01,
                "{mode:?} {hz} Hz: the prop missed"
            );
            assert!(
                deep_unset > 0.01,
                "nothing shared: the chain does not see the prop"
            );
            assert_eq!(frames, 0, "{mode:?} {hz} Hz: {deep} m inside");
        }
    }
}

/// The keys: `[[collider_group]]` and `use_shared_collision` read and written back; a group
/// naming a collider the rig does not define, two groups of one name, a nameless one,
/// refused by name.
#[test]
fn keys_are_read_written_and_refused() {
    let text = "[[chain]]\nname = \"hair\"\nroot = \"hair_0\"\nuse_shared_collision = true\n\n\
                [[collider]]\nname = \"head\"\nbone = \"hair_0\"\nshape = \"sphere\"\nradius = 0.1\n\n\
                [[collider_group]]\nname = \"body\"\ncolliders = [\"head\"]\n";
    let rig = RigSettings::from_toml_str(text).unwrap();
    assert!(rig.chains[0].use_shared_collision);
    assert_eq!(rig.collider_groups[0].colliders, vec!["head".to_string()]);
    let back = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
    assert_eq!(back, rig);
    let plain = RigSettings::from_toml_str("[[chain]]\nroot = \"hair_0\"\n").unwrap();
    let written = plain.to_toml_string().unwrap();
    assert!(!written.contains("use_shared_collision") && !written.contains("collider_group"));
    for (bad, needle) in [
        (
            text.replace("colliders = [\"head\"]", "colliders = [\"hat\"]"),
            "collider group 'body' names collider 'hat'",
        ),
        (
            format!("{text}\n[[collider_group]]\nname = \"body\"\ncolliders = []\n"),
            "two collider groups are named 'body'",
        ),
        (
            text.replace("name = \"body\"", "name = \"\""),
            "a [[collider_group]] has no name",
        ),
        (
            text.replace("use_shared_collision = true", "use_shared_collision = 1"),
            "use_shared_collision",
        ),
    ] {
        let e = RigSettings::from_toml_str(&bad).unwrap_err().to_string();
        assert!(e.contains(needle), "{needle}: {e}");
    }
    // Such a rig steps per character in crowds; without the key it does not.
    let sim = CharacterSim::new(skeleton(), &rig).unwrap();
    assert!(sim.rig().chains().uses_shared_collision());
    assert!(sim.rig().chains().needs_per_character());
    let sim = CharacterSim::new(skeleton(), &plain).unwrap();
    assert!(!sim.rig().chains().needs_per_character());
}

/// Shared colliders are checked: a shape out of range, a transform that is not finite,
/// named by index, nothing changed; an unknown group refused by name; an empty set clears.
#[test]
fn bad_shared_colliders_and_groups_are_refused() {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &cape(TimeMode::Fixed, true)).unwrap();
    let ok = PlacedCollider {
        shape: Shape::Sphere {
            radius: 0.1,
            inside: false,
        },
        transform: Transform::from_translation(Vec3::new(0.0, 1.4, -0.1)),
    };
    sim.set_shared_colliders(&[ok]).unwrap();
    for (bad, needle) in [
        (
            PlacedCollider {
                shape: Shape::Sphere {
                    radius: -1.0,
                    inside: false,
                },
                ..ok
            },
            "shared collider 1",
        ),
        (
            PlacedCollider {
                transform: Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
                ..ok
            },
            "shared collider 1",
        ),
    ] {
        let e = sim
            .set_shared_colliders(&[ok, bad])
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{e}");
        assert_eq!(sim.chain_state().shared_colliders().len(), 1, "unchanged");
    }
    sim.frame(sk.rest(), Transform::IDENTITY, 1.0 / 60.0)
        .unwrap();
    sim.clear_shared_colliders();
    assert!(sim.chain_state().shared_colliders().is_empty());
    sim.frame(sk.rest(), Transform::IDENTITY, 1.0 / 60.0)
        .unwrap();
    let (hsk, hrig) = holder();
    let mut h = CharacterSim::new(hsk.clone(), &hrig).unwrap();
    h.frame(hsk.rest(), Transform::IDENTITY, 0.0).unwrap();
    let e = h.shared_colliders(Some("sword")).unwrap_err().to_string();
    assert!(e.contains("'sword'"), "{e}");
    // Every collider without a group; the group's alone with it.
    assert_eq!(h.shared_colliders(None).unwrap().len(), 1);
    let world = h.shared_colliders(Some("prop")).unwrap();
    assert_eq!(world[0].transform.translation, Vec3::ZERO);
}

/// A chain without `use_shared_collision` on the same character ignores the shared
/// colliders: its bits are those of a run with nothing shared.
#[test]
fn chains_that_do_not_ask_ignore_them() {
    let sk = skeleton();
    let rig = cape(TimeMode::Fixed, false);
    let mut with = CharacterSim::new(sk.clone(), &rig).unwrap();
    let mut without = CharacterSim::new(sk.clone(), &rig).unwrap();
    let ball = PlacedCollider {
        shape: Shape::Sphere {
            radius: 0.2,
            inside: false,
        },
        transform: Transform::from_translation(Vec3::new(0.0, 1.4, -0.15)),
    };
    with.set_shared_colliders(&[ball]).unwrap();
    for f in 0..60 {
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        let comp = Transform::from_translation(Vec3::new(0.1 * (f as f32 * 0.1).sin(), 0.0, 0.0));
        with.frame(sk.rest(), comp, dt).unwrap();
        without.frame(sk.rest(), comp, dt).unwrap();
        common::assert_pose_bits(&sk, "ignored", with.pose(), without.pose());
    }
}
