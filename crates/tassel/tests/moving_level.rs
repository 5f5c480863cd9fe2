//! Levels that change between frames (issue 18): a moving, turning platform carries the
//! character; a closing door pushes it out, never through; a removed collider is gone;
//! collision groups filter; a moved collider's BVH leaves follow it. Expected values come
//! from the platform's and the door's own motion, worked out by hand.

use glam::{Quat, Vec3};
use tassel::controller::{
    CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape, Movement,
};
use tassel::Transform;

const DT: f32 = 1.0 / 60.0;
const G: f32 = 9.81;
const CAPSULE: CharacterCapsule = CharacterCapsule {
    radius: 0.3,
    half_height: 0.6,
};
/// Centre above the bottom.
const HALF: f32 = 0.9;

fn boxed(name: &str, centre: Vec3, half: Vec3) -> LevelCollider {
    LevelCollider::new(name, LevelShape::Box { half_extents: half }, centre)
}

fn floor() -> LevelCollider {
    boxed(
        "floor",
        Vec3::new(0.0, -0.5, 0.0),
        Vec3::new(100.0, 0.5, 100.0),
    )
}

/// A character moved like a game moves it: gravity integrated by the caller, cleared on
/// the ground; its facing turned by what carries it.
struct Walker {
    s: ControllerSettings,
    pos: Vec3,
    facing: Quat,
    vy: f32,
    grounded: bool,
}

impl Walker {
    fn at(pos: Vec3) -> Self {
        Self {
            s: ControllerSettings::default(),
            pos,
            facing: Quat::IDENTITY,
            vy: 0.0,
            grounded: true,
        }
    }

    fn step(&mut self, level: &Level, horizontal: Vec3) -> Movement {
        if self.grounded {
            self.vy = 0.0;
        }
        self.vy -= G * DT;
        let desired = horizontal * DT + Vec3::Y * self.vy * DT;
        let m = self
            .s
            .move_shape(
                level,
                &CAPSULE,
                &Transform::from_translation(self.pos),
                desired,
                DT,
            )
            .unwrap();
        assert!(m.translation.is_finite());
        self.pos += m.translation;
        self.facing = m.platform_rotation * self.facing;
        self.grounded = m.grounded;
        m
    }

    fn penetration(&self, level: &Level) -> f32 {
        level.capsule_penetration(
            CAPSULE.radius,
            CAPSULE.half_height,
            self.pos,
            Quat::IDENTITY,
        )
    }
}

/// A 4 × 4 m platform, 0.3 m thick, moving at 2 m/s along a circle's tangent while it turns
/// at 30°/s (and bobbing 0.2 m up and down): the feet of a character standing on it stay
/// on the same point of the platform within 1 mm over 5 s, and its facing turns with it.
#[test]
fn a_moving_turning_platform_carries_the_character() {
    let mut level = Level::new(vec![floor()]).unwrap();
    let pose = |t: f32| {
        let yaw = 30f32.to_radians() * t;
        let centre = Vec3::new(2.0 * t, 1.0 + 0.2 * (1.3 * t).sin(), 0.5 * t);
        (centre, Quat::from_rotation_y(yaw))
    };
    let (c0, r0) = pose(0.0);
    let platform = level
        .add(boxed("platform", c0, Vec3::new(2.0, 0.15, 2.0)).rotated(r0))
        .unwrap();
    // Standing off-centre: 1.2 m along x and −0.7 m along z of the platform's frame.
    let local_feet = Vec3::new(1.2, 0.15 + 0.01, -0.7);
    let feet = c0 + r0 * local_feet;
    let mut w = Walker::at(feet + Vec3::Y * HALF);
    let mut worst = 0.0f32;
    let mut carried = 0;
    for f in 1..=300 {
        let t = f as f32 * DT;
        level.start_frame();
        let (c, r) = pose(t);
        level.set_pose(platform, c, r).unwrap();
        let m = w.step(&level, Vec3::ZERO);
        carried += (m.platform == Some(platform)) as usize;
        assert!(m.grounded, "frame {f}: fell off at {}", w.pos);
        let feet_now = w.pos - Vec3::Y * HALF;
        let local = r.inverse() * (feet_now - c);
        worst = worst.max((local - local_feet).length());
        assert!(w.penetration(&level) < 1e-3);
    }
    assert_eq!(carried, 300, "carried on {carried} of 300 frames");
    assert!(worst < 1e-3, "feet strayed {worst} m on the platform");
    // 150° in 5 s, about +Y.
    let (axis, angle) = w.facing.to_axis_angle();
    assert!(
        (angle.to_degrees() - 150.0).abs() < 0.1 && axis.abs_diff_eq(Vec3::Y, 1e-3),
        "facing turned {}° about {axis}",
        angle.to_degrees()
    );
}

/// Walking on a platform that moves: the walk is relative to the ground under the feet.
#[test]
fn walking_on_a_moving_platform_adds_its_motion() {
    let mut level = Level::new(vec![floor()]).unwrap();
    let top = 1.0;
    let platform = level
        .add(boxed(
            "platform",
            Vec3::new(0.0, top - 0.15, 0.0),
            Vec3::new(10.0, 0.15, 10.0),
        ))
        .unwrap();
    let mut w = Walker::at(Vec3::new(0.0, top + 0.01 + HALF, 0.0));
    for f in 1..=120 {
        level.start_frame();
        let x = 1.5 * f as f32 * DT;
        level
            .set_pose(platform, Vec3::new(x, top - 0.15, 0.0), Quat::IDENTITY)
            .unwrap();
        w.step(&level, Vec3::new(0.0, 0.0, 1.0));
    }
    // 2 s: 3 m carried along x, 2 m walked along z.
    assert!((w.pos.x - 3.0).abs() < 2e-3, "{}", w.pos);
    assert!((w.pos.z - 2.0).abs() < 2e-3, "{}", w.pos);
}

/// A door (a 10 cm slab) closes on a character standing still, at 2, 20 and 40 m/s (at
/// 40, two thirds of a metre per frame: more than the capsule's width and the door's
/// together, so that without the sweep the door would pass it untouched): the character
/// always ends on the door's closing side, in front of it, never inside and never through.
#[test]
fn a_closing_door_pushes_the_character_out_never_through() {
    for speed in [2.0f32, 20.0, 40.0] {
        let mut level = Level::new(vec![floor()]).unwrap();
        let half = Vec3::new(0.05, 1.2, 1.5);
        let door_x = |t: f32| -1.0 + speed * t;
        let door = level
            .add(boxed("door", Vec3::new(door_x(0.0), 1.2, 0.0), half))
            .unwrap();
        let mut w = Walker::at(Vec3::new(0.0, 0.01 + HALF, 0.0));
        let frames = (3.0 / speed / DT).ceil() as usize + 5;
        for f in 1..=frames {
            level.start_frame();
            let x = door_x(f as f32 * DT);
            level
                .set_pose(door, Vec3::new(x, 1.2, 0.0), Quat::IDENTITY)
                .unwrap();
            w.step(&level, Vec3::ZERO);
            let front = x + half.x;
            assert!(
                w.pos.x - CAPSULE.radius >= front - 1e-3,
                "speed {speed}, frame {f}: the door's face is at {front}, the character's back at {}",
                w.pos.x - CAPSULE.radius
            );
            assert!(w.penetration(&level) < 1e-3, "speed {speed}, frame {f}");
        }
        assert!(w.pos.x > 1.5, "speed {speed}: not pushed along: {}", w.pos);
    }
}

/// A bridge over a pit removed while the character walks on it: it falls; a wall removed
/// in front of it no longer blocks.
#[test]
fn a_removed_collider_is_gone() {
    let pit_floor = boxed("pit", Vec3::new(0.0, -5.5, 0.0), Vec3::new(50.0, 0.5, 50.0));
    let bridge = boxed(
        "bridge",
        Vec3::new(0.0, -0.25, 0.0),
        Vec3::new(1.0, 0.25, 20.0),
    );
    let wall = boxed("wall", Vec3::new(0.0, 1.0, 3.0), Vec3::new(2.0, 1.0, 0.1));
    let mut level = Level::new(vec![pit_floor, bridge, wall]).unwrap();
    assert_eq!(level.len(), 3);
    let mut w = Walker::at(Vec3::new(0.0, 0.01 + HALF, 0.0));
    for _ in 0..120 {
        w.step(&level, Vec3::new(0.0, 0.0, 1.5));
    }
    // Blocked by the wall: its near face at z = 2.9, the capsule a radius and a skin short.
    assert!((w.pos.z - (2.9 - 0.3 - 0.01)).abs() < 2e-3, "{}", w.pos);
    assert_eq!(level.remove(2).map(|c| c.name), Some("wall".into()));
    assert!(level.remove(2).is_none(), "removed twice");
    assert_eq!(level.len(), 2);
    for _ in 0..60 {
        w.step(&level, Vec3::new(0.0, 0.0, 1.5));
    }
    assert!(w.pos.z > 3.5, "still blocked: {}", w.pos);
    assert!(w.grounded);
    assert!(level.remove(1).is_some());
    let y0 = w.pos.y;
    for _ in 0..30 {
        w.step(&level, Vec3::ZERO);
    }
    // Half a second of free fall from rest: the caller's Euler gives g·dt²·n(n+1)/2.
    let n = 30.0;
    let fall = G * DT * DT * n * (n + 1.0) / 2.0;
    assert!(
        (y0 - w.pos.y - fall).abs() < 1e-3,
        "fell {} m, not {fall}",
        y0 - w.pos.y
    );
    assert!(!w.grounded);
}

/// Added and moved colliders are found by every query (their BVH leaves follow them);
/// ids stay stable across removals.
#[test]
fn added_and_moved_colliders_block_where_they_are() {
    let mut level = Level::new(vec![floor()]).unwrap();
    let wall = level
        .add(boxed(
            "wall",
            Vec3::new(0.0, 1.0, 50.0),
            Vec3::new(2.0, 1.0, 0.1),
        ))
        .unwrap();
    assert_eq!(wall, 1);
    let hit = |level: &Level| level.ray(Vec3::new(0.0, 1.0, 0.0), Vec3::Z, 100.0);
    assert!((hit(&level).unwrap().distance - 49.9).abs() < 1e-4);
    level.start_frame();
    level
        .set_pose(wall, Vec3::new(0.0, 1.0, 5.0), Quat::IDENTITY)
        .unwrap();
    assert!((hit(&level).unwrap().distance - 4.9).abs() < 1e-4);
    let (lo, hi) = level.bounds(wall).unwrap();
    assert!(
        lo.abs_diff_eq(Vec3::new(-2.0, 0.0, 4.9), 1e-5)
            && hi.abs_diff_eq(Vec3::new(2.0, 2.0, 5.1), 1e-5)
    );
    // Moved away sideways: the ray along z passes.
    level
        .set_pose(wall, Vec3::new(30.0, 1.0, 5.0), Quat::IDENTITY)
        .unwrap();
    assert!(hit(&level).is_none());
    // One motion per frame, from where it was at start_frame.
    let (from, to) = level.motion(wall).unwrap();
    assert_eq!(from.translation, Vec3::new(0.0, 1.0, 50.0));
    assert_eq!(to.translation, Vec3::new(30.0, 1.0, 5.0));
    level.start_frame();
    assert!(level.motion(wall).is_none());
    // A removed id is not reused.
    level.remove(wall).unwrap();
    let again = level
        .add(boxed(
            "wall 2",
            Vec3::new(0.0, 1.0, 7.0),
            Vec3::new(2.0, 1.0, 0.1),
        ))
        .unwrap();
    assert_eq!(again, 2);
    assert!((hit(&level).unwrap().distance - 6.9).abs() < 1e-4);
    assert!(level.set_pose(wall, Vec3::ZERO, Quat::IDENTITY).is_err());
    assert!(level
        .set_pose(again, Vec3::new(f32::NAN, 0.0, 0.0), Quat::IDENTITY)
        .is_err());
    assert_eq!(
        level.collider(again).unwrap().position,
        Vec3::new(0.0, 1.0, 7.0)
    );
}

/// A collider in a group the character does not collide with is walked through; the same
/// collider in the default group blocks.
#[test]
fn collision_groups_filter_what_blocks() {
    let glass = |groups| {
        boxed("glass", Vec3::new(0.0, 1.0, 2.0), Vec3::new(2.0, 1.0, 0.1)).with_groups(groups)
    };
    for (groups, passes) in [(0b10u32, true), (0b01, false), (0b11, false)] {
        let level = Level::new(vec![floor(), glass(groups)]).unwrap();
        let mut w = Walker::at(Vec3::new(0.0, 0.01 + HALF, 0.0));
        w.s.collide_with = !0b10;
        for _ in 0..120 {
            w.step(&level, Vec3::new(0.0, 0.0, 2.0));
        }
        assert_eq!(w.pos.z > 3.0, passes, "groups {groups:b}: at {}", w.pos);
        assert!(w.grounded);
    }
}
