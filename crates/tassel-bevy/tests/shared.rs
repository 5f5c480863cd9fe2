//! Shared collision in Bevy: a `SharedCollisionSource` holding a ball swung through the
//! chain of a `SharedCollisionTarget` (its chain with `use_shared_collision`). The chain's
//! bones never end a frame inside the ball where it is this frame (the colliders handed
//! over are this frame's); without the target component they go through; an unknown group
//! is reported.

mod common;

use bevy::prelude::*;
use common::*;
use tassel::collide::Shape;
use tassel::dynamics::{ColliderGroupSettings, ColliderSettings, RigSettings};
use tassel_bevy::prelude::*;

const BALL_R: f32 = 0.06;
const POINT_R: f32 = 0.02;

#[derive(Component)]
struct Swung;

fn swing(time: Res<Time>, mut q: Query<&mut Transform, With<Swung>>) {
    for mut t in &mut q {
        let s = time.elapsed_secs();
        t.translation = Vec3::new(0.5 * (std::f32::consts::TAU * s).sin(), 1.42, -0.16);
    }
}

/// A one-bone holder of a ball (group `prop`) and a 6-bone hanging chain.
fn skeletons() -> (tassel::Skeleton, tassel::Skeleton) {
    let hand = tassel::Skeleton::new(
        vec!["hand".into()],
        vec![None],
        vec![tassel::Transform::IDENTITY],
    )
    .unwrap();
    let mut names = vec!["hair_0".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![tassel::Transform::from_translation(
        tassel::glam::Vec3::new(0.0, 1.62, -0.1),
    )];
    for i in 1..=6 {
        names.push(format!("hair_{i}"));
        parents.push(Some(i - 1));
        rest.push(tassel::Transform::from_translation(
            tassel::glam::Vec3::new(0.004 * (i - 1) as f32, -0.06, -0.015),
        ));
    }
    (hand, tassel::Skeleton::new(names, parents, rest).unwrap())
}

/// Runs `frames` frames at 60 Hz with the source sharing `group`; returns the deepest a chain bone
/// went into the ball where it is this frame (metres; ≤ 0: never), how many colliders
/// were handed over at the end, and the app.
fn run(target: bool, group: &str, frames: usize) -> (f32, usize, App) {
    let mut app = app(60.0);
    app.add_systems(Update, swing);
    let (hand, hair) = skeletons();
    let holder_rig = RigSettings {
        colliders: vec![ColliderSettings {
            mirror: None,
            mirror_bone: String::new(),
            name: "ball".into(),
            bone: "hand".into(),
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            shape: Shape::Sphere {
                radius: BALL_R,
                inside: false,
            },
        }],
        collider_groups: vec![ColliderGroupSettings {
            name: "prop".into(),
            colliders: vec!["ball".into()],
        }],
        ..Default::default()
    };
    let chain = tassel::dynamics::chain::ChainSettings {
        name: "cape".into(),
        root: "hair_0".into(),
        radius: POINT_R,
        use_shared_collision: true,
        ..Default::default()
    };
    let cape_rig = RigSettings {
        chains: vec![chain],
        ..Default::default()
    };
    let world = app.world_mut();
    let hand_model = world
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(hand.clone(), None));
    let hair_model = world
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(hair.clone(), None));
    let holder_rig = world
        .resource_mut::<Assets<TasselRig>>()
        .add(TasselRig(holder_rig));
    let cape_rig = world
        .resource_mut::<Assets<TasselRig>>()
        .add(TasselRig(cape_rig));
    let source = world
        .spawn((
            Transform::default(),
            Swung,
            SecondaryMotion::new(hand_model).with_rig(holder_rig),
            SharedCollisionSource::group(group),
        ))
        .id();
    spawn_skeleton(app.world_mut(), &hand, source);
    let cape = app
        .world_mut()
        .spawn((
            Transform::default(),
            SecondaryMotion::new(hair_model).with_rig(cape_rig),
        ))
        .id();
    if target {
        app.world_mut()
            .entity_mut(cape)
            .insert(SharedCollisionTarget::new([source]));
    }
    let bones = spawn_skeleton(app.world_mut(), &hair, cape);
    let mut deepest = f32::NEG_INFINITY;
    for _ in 0..frames {
        app.update();
        let w = app.world();
        let ball = w.get::<Transform>(source).unwrap().translation;
        for &b in &bones[1..] {
            let x = w.get::<GlobalTransform>(b).unwrap().translation();
            deepest = deepest.max(BALL_R + POINT_R - x.distance(ball));
        }
    }
    let handed = app
        .world()
        .get::<SharedCollisionTarget>(cape)
        .map_or(0, |t| t.colliders().len());
    (deepest, handed, app)
}

#[test]
fn a_shared_ball_keeps_out_of_the_target_chain() {
    let (deepest, handed, _) = run(true, "prop", 120);
    let (off, _, _) = run(false, "prop", 120);
    println!(
        "a ball swung at up to 3.1 m/s through a chain in Bevy: {:.3} mm into it with \
         shared collision, {:.1} mm without the target component",
        1e3 * deepest.max(0.0),
        1e3 * off
    );
    assert_eq!(handed, 1);
    assert!(off > 0.01, "the ball misses the chain ({off} m)");
    assert!(deepest <= 1e-4, "{deepest} m inside");
}

#[test]
fn an_unknown_group_is_reported() {
    // (Messages live two frames: read them right after the first ones.)
    let (_, handed, mut app) = run(true, "sword", 3);
    assert_eq!(handed, 0, "nothing was handed over");
    let errors: Vec<String> = app
        .world_mut()
        .resource_mut::<Messages<TasselError>>()
        .drain()
        .map(|e| e.message)
        .collect();
    assert!(errors.iter().any(|e| e.contains("'sword'")), "{errors:?}");
}
