//! The character controller as components, headless: colliders from entities (added,
//! moved, despawned) and a capsule character, checked against the core controller run on
//! the same level and inputs (bit for bit), and against the platform's own motion.

mod common;

use bevy::prelude::*;
use common::{app, Errors};
use tassel::controller::{CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape};
use tassel_bevy::prelude::*;

const HZ: f64 = 60.0;
const G: f32 = 9.81;

fn capsule() -> CharacterCapsule {
    CharacterCapsule {
        radius: 0.3,
        half_height: 0.6,
    }
}

fn floor_shape() -> LevelShape {
    LevelShape::Box {
        half_extents: Vec3::new(50.0, 0.5, 50.0),
    }
}

fn platform_shape() -> LevelShape {
    LevelShape::Box {
        half_extents: Vec3::new(2.0, 0.15, 2.0),
    }
}

/// The platform's pose at frame `f` (moving at 2 m/s and turning 30°/s).
fn platform_pose(f: u32) -> (Vec3, Quat) {
    let t = f as f32 / HZ as f32;
    (
        Vec3::new(2.0 * t, 1.0, 0.0),
        Quat::from_rotation_y(30f32.to_radians() * t),
    )
}

#[derive(Component)]
struct Platform;

#[derive(Resource, Default)]
struct Frame(u32);

/// Moves the platform in `Update` and asks the character to fall by gravity (the caller's
/// semi-implicit Euler, cleared on the ground).
fn drive(
    mut frame: ResMut<Frame>,
    mut platforms: Query<&mut Transform, With<Platform>>,
    mut characters: Query<&mut CharacterController>,
    mut vy: Local<f32>,
) {
    frame.0 += 1;
    for mut t in &mut platforms {
        let (p, r) = platform_pose(frame.0);
        t.translation = p;
        t.rotation = r;
    }
    let dt = 1.0 / HZ as f32;
    for mut c in &mut characters {
        if c.last.grounded {
            *vy = 0.0;
        }
        *vy -= G * dt;
        c.desired = Vec3::Y * *vy * dt;
    }
}

/// A character standing on a moving, turning platform entity moves exactly as the core
/// controller moves it on the same level and inputs, and stays on its platform point.
#[test]
fn a_platform_entity_carries_a_controlled_character_as_the_core_does() {
    let mut app = app(HZ);
    app.init_resource::<Frame>().add_systems(Update, drive);
    let (p0, r0) = platform_pose(0);
    let local_feet = Vec3::new(1.2, 0.15 + 0.01, -0.7);
    let start = p0 + r0 * local_feet + Vec3::Y * 0.9;
    let world = app.world_mut();
    world.spawn((
        TasselCollider::new(floor_shape()),
        Transform::from_xyz(0.0, -0.5, 0.0),
    ));
    world.spawn((
        TasselCollider::new(platform_shape()),
        Transform::from_translation(p0).with_rotation(r0),
        Platform,
    ));
    let character = world
        .spawn((
            CharacterController::new(capsule()),
            Transform::from_translation(start),
        ))
        .id();
    // The core, by hand: the same colliders, moved the same way. The plugin first sees the
    // platform in frame 1, after `Update` has moved it there: it enters the level at that
    // pose, without a motion.
    let (p1, r1) = platform_pose(1);
    let mut level = Level::new(vec![
        LevelCollider::new("floor", floor_shape(), Vec3::new(0.0, -0.5, 0.0)),
        LevelCollider::new("platform", platform_shape(), p1).rotated(r1),
    ])
    .unwrap();
    let s = ControllerSettings::default();
    let (mut pos, mut rot, mut vy, mut grounded) = (start, Quat::IDENTITY, 0.0f32, false);
    let dt = 1.0 / HZ as f32;
    let mut on_platform = Vec3::ZERO;
    for f in 1..=240u32 {
        app.update();
        level.start_frame();
        let (p, r) = platform_pose(f);
        if f > 1 {
            level.set_pose(1, p, r).unwrap();
        }
        // The first update has dt = 0 in Bevy (Time starts there): the same in the core.
        let step = if f == 1 { 0.0 } else { dt };
        if grounded {
            vy = 0.0;
        }
        vy -= G * dt;
        let pose = tassel::Transform {
            translation: pos,
            rotation: rot,
            scale: Vec3::ONE,
        };
        let m = s
            .move_shape(&level, &capsule(), &pose, Vec3::Y * vy * dt, step)
            .unwrap();
        pos += m.translation;
        if m.platform_rotation != Quat::IDENTITY {
            rot = (m.platform_rotation * rot).normalize();
        }
        grounded = m.grounded;
        let t = app.world().get::<Transform>(character).unwrap();
        assert_eq!(t.translation, pos, "frame {f}");
        assert_eq!(t.rotation, rot, "frame {f}");
        let c = app.world().get::<CharacterController>(character).unwrap();
        assert_eq!(c.last.grounded, grounded, "frame {f}");
        // Where the feet are on the platform: from frame 1 on (before, the platform was
        // not yet in the level, so it moved under the feet once), the same point.
        let feet = r.inverse() * (pos - Vec3::Y * 0.9 - p);
        if f == 1 {
            on_platform = feet;
            assert!((feet - local_feet).length() < 0.05);
        } else {
            assert!(grounded, "frame {f}: fell off at {pos}");
            assert!(
                (feet - on_platform).length() < 1e-3,
                "frame {f}: feet at {feet} on the platform, {on_platform} at frame 1"
            );
        }
    }
    // It was carried by the platform entity.
    let level_res = app.world().resource::<TasselLevel>();
    let c = app.world().get::<CharacterController>(character).unwrap();
    let platform = c.last.platform.and_then(|id| level_res.entity(id));
    assert!(platform.is_some_and(|e| app.world().get::<Platform>(e).is_some()));
    assert!(app.world().resource::<Errors>().0.is_empty());
}

/// Despawning a collider entity removes it from the level: the character standing on it
/// falls; a collider with a parent is placed by the composed transform.
#[test]
fn despawned_colliders_leave_the_level_and_children_are_placed_in_the_world() {
    let mut app = app(HZ);
    app.init_resource::<Frame>().add_systems(Update, drive);
    let world = app.world_mut();
    let holder = world.spawn(Transform::from_xyz(10.0, 0.0, 0.0)).id();
    let bridge = world
        .spawn((
            TasselCollider::new(LevelShape::Box {
                half_extents: Vec3::new(1.0, 0.25, 1.0),
            }),
            Transform::from_xyz(-10.0, -0.25, 0.0),
            ChildOf(holder),
        ))
        .id();
    let character = world
        .spawn((
            CharacterController::new(capsule()),
            Transform::from_xyz(0.0, 0.91, 0.0),
        ))
        .id();
    for _ in 0..30 {
        app.update();
    }
    let level = app.world().resource::<TasselLevel>();
    let id = level.collider_id(bridge).unwrap();
    let (lo, hi) = level.level().bounds(id).unwrap();
    assert!(
        lo.abs_diff_eq(Vec3::new(-1.0, -0.5, -1.0), 1e-5)
            && hi.abs_diff_eq(Vec3::new(1.0, 0.0, 1.0), 1e-5),
        "{lo} {hi}"
    );
    let y = app
        .world()
        .get::<Transform>(character)
        .unwrap()
        .translation
        .y;
    assert!((y - 0.91).abs() < 1e-3, "rests at {y}");
    app.world_mut().entity_mut(bridge).despawn();
    for _ in 0..30 {
        app.update();
    }
    assert!(app.world().resource::<TasselLevel>().level().is_empty());
    let y2 = app
        .world()
        .get::<Transform>(character)
        .unwrap()
        .translation
        .y;
    assert!(y2 < y - 0.5, "did not fall: {y2}");
    assert!(app.world().resource::<Errors>().0.is_empty());
}
