//! The character controller, scenario by scenario (issue 6). Expected values come from the
//! level's geometry worked out by hand, closed-form free fall and projection formulas, and
//! invariants (never inside a collider, never through a wall, at rest in a corner).

use glam::{Quat, Vec3};
use tassel::controller::{
    CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape, Movement,
};
use tassel::Transform;

const DT: f32 = 1.0 / 60.0;
const G: f32 = 9.81;
/// 1.8 m tall, 0.3 m radius: the centre is 0.9 m above the bottom.
const CAPSULE: CharacterCapsule = CharacterCapsule {
    radius: 0.3,
    half_height: 0.6,
};
const HALF: f32 = 0.9;

fn floor() -> LevelCollider {
    LevelCollider::new(
        "floor",
        LevelShape::Box {
            half_extents: Vec3::new(50.0, 0.5, 50.0),
        },
        Vec3::new(0.0, -0.5, 0.0),
    )
}

fn block(name: &str, min: Vec3, max: Vec3) -> LevelCollider {
    LevelCollider::new(
        name,
        LevelShape::Box {
            half_extents: (max - min) * 0.5,
        },
        (max + min) * 0.5,
    )
}

/// A character driven like a game does: horizontal velocity from input, gravity
/// integrated by the caller and cleared on the ground.
struct Walker {
    settings: ControllerSettings,
    pos: Vec3,
    vy: f32,
    grounded: bool,
}

impl Walker {
    fn standing_at(x: f32, bottom: f32, z: f32) -> Self {
        Self {
            settings: ControllerSettings::default(),
            pos: Vec3::new(x, bottom + HALF, z),
            vy: 0.0,
            grounded: false,
        }
    }

    fn bottom(&self) -> f32 {
        self.pos.y - HALF
    }

    fn step(&mut self, level: &Level, horizontal: Vec3, dt: f32) -> Movement {
        if self.grounded {
            self.vy = 0.0;
        }
        self.vy -= G * dt;
        let desired = horizontal * dt + Vec3::Y * self.vy * dt;
        let m = self
            .settings
            .move_shape(
                level,
                &CAPSULE,
                &Transform::from_translation(self.pos),
                desired,
                dt,
            )
            .unwrap();
        assert!(m.translation.is_finite());
        self.pos += m.translation;
        self.grounded = m.grounded;
        if !m.grounded && dt > 0.0 && m.translation.y > desired.y + 1e-6 {
            // Stopped or deflected vertically (a slope, a ceiling): keep what was realised.
            self.vy = m.translation.y / dt;
        }
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

#[test]
fn falls_and_lands_grounded() {
    let level = Level::new(vec![floor()]).unwrap();
    let mut w = Walker::standing_at(0.0, 2.0, 0.0);
    let skin = w.settings.skin;
    // By hand: the caller's semi-implicit Euler falls g·dt²·k(k+1)/2 after k frames; the
    // first frame whose fall reaches 2 m − skin is the landing frame.
    let mut landing = 0;
    while G * DT * DT * (landing * (landing + 1)) as f32 / 2.0 < 2.0 - skin {
        landing += 1;
    }
    let mut first_grounded = None;
    for f in 1..=120 {
        let m = w.step(&level, Vec3::ZERO, DT);
        assert!(
            w.bottom() >= -1e-5,
            "frame {f}: bottom {} below the floor",
            w.bottom()
        );
        if m.grounded && first_grounded.is_none() {
            first_grounded = Some(f);
        }
        if f > landing {
            assert!(m.grounded, "frame {f}: not grounded after landing");
        }
    }
    let f = first_grounded.expect("never grounded");
    // The probe reaches 2·skin below, so it may report the ground one frame early.
    assert!(
        f == landing || f + 1 == landing,
        "grounded at frame {f}, free fall lands at frame {landing}"
    );
    assert!(
        (w.bottom() - skin).abs() < 1e-3,
        "rests {} above the floor, skin is {skin}",
        w.bottom()
    );
}

/// `count` steps of `rise` × `tread` going up along +x from x = `start`.
fn stairs(start: f32, count: usize, rise: f32, tread: f32) -> Vec<LevelCollider> {
    (0..count)
        .map(|i| {
            let x0 = start + i as f32 * tread;
            block(
                &format!("step {i}"),
                Vec3::new(x0, 0.0, -2.0),
                Vec3::new(
                    start + count as f32 * tread + 2.0,
                    (i + 1) as f32 * rise,
                    2.0,
                ),
            )
        })
        .collect()
}

#[test]
fn climbs_small_stairs_and_is_blocked_by_high_ones() {
    // 0.2 m steps with a 0.3 m maximum step: climbed to the top (5 × 0.2 = 1 m).
    let mut colliders = vec![floor()];
    colliders.extend(stairs(1.0, 5, 0.2, 0.3));
    let level = Level::new(colliders).unwrap();
    let mut w = Walker::standing_at(0.0, 0.01, 0.0);
    let mut stepped = 0;
    // 2.5 s at 1.5 m/s: 3.75 m, onto the top (it ends at x = 4.5).
    for _ in 0..150 {
        let m = w.step(&level, Vec3::new(1.5, 0.0, 0.0), DT);
        stepped += m.stepped as usize;
        assert!(w.penetration(&level) < 1e-3, "inside a step at {}", w.pos);
    }
    assert!(w.pos.x > 1.0 + 5.0 * 0.3, "stopped at x = {}", w.pos.x);
    assert!(
        (w.bottom() - (1.0 + w.settings.skin)).abs() < 2e-3,
        "ends at height {} instead of on the 1 m top",
        w.bottom()
    );
    assert!(stepped >= 5, "{stepped} steps climbed");

    // 0.4 m steps: the first riser blocks. The capsule's front stays before x = 1.
    let mut colliders = vec![floor()];
    colliders.extend(stairs(1.0, 3, 0.4, 0.3));
    let level = Level::new(colliders).unwrap();
    let mut w = Walker::standing_at(0.0, 0.01, 0.0);
    for f in 0..240 {
        let m = w.step(&level, Vec3::new(1.5, 0.0, 0.0), DT);
        assert!(!m.stepped, "frame {f}: stepped onto a 0.4 m step");
        assert!(
            w.pos.x + CAPSULE.radius <= 1.0 + 1e-4,
            "passed the riser: {}",
            w.pos
        );
        assert!(w.bottom() < 0.05, "climbed to {}", w.bottom());
    }
    assert!(
        w.pos.x + CAPSULE.radius > 1.0 - 0.02,
        "did not reach the riser: {}",
        w.pos
    );
}

/// A ramp rising along +z from z = `z0`, with a platform at its top.
fn ramp_level(angle_deg: f32, length: f32, z0: f32) -> (Level, f32) {
    let height = length * angle_deg.to_radians().tan();
    let level = Level::new(vec![
        floor(),
        LevelCollider::new(
            "ramp",
            LevelShape::ramp_with_angle(4.0, length, angle_deg),
            Vec3::new(0.0, 0.0, z0),
        ),
        block(
            "platform",
            Vec3::new(-2.0, 0.0, z0 + length),
            Vec3::new(2.0, height, z0 + length + 10.0),
        ),
    ])
    .unwrap();
    (level, height)
}

#[test]
fn walks_up_a_30_degree_ramp() {
    let (level, height) = ramp_level(30.0, 3.0, 1.0);
    let mut w = Walker::standing_at(0.0, 0.01, 0.0);
    w.grounded = true;
    let mut max_gap = 0.0f32;
    for f in 0..240 {
        let m = w.step(&level, Vec3::new(0.0, 0.0, 2.0), DT);
        assert!(m.grounded, "frame {f}: lost the ground at {}", w.pos);
        assert!(w.penetration(&level) < 1e-3);
        // On the ramp, the bottom point of the capsule's sphere touches the slope where the
        // slope's normal passes through the sphere's centre: by hand, the bottom of the
        // capsule is then r(1/cos30° − 1) above the slope line under its axis.
        let z = w.pos.z;
        if (1.5..3.5).contains(&z) {
            let slope_y = (z - 1.0) * 30f32.to_radians().tan();
            let rest = CAPSULE.radius * (1.0 / 30f32.to_radians().cos() - 1.0);
            max_gap = max_gap.max((w.bottom() - slope_y - rest).abs());
        }
    }
    assert!(max_gap < 0.03, "strayed {max_gap} m from the slope");
    assert!(w.pos.z > 4.5, "did not reach the top: {}", w.pos);
    assert!(
        (w.bottom() - height - w.settings.skin).abs() < 2e-3,
        "ends at {}",
        w.bottom()
    );
}

#[test]
fn slides_down_a_60_degree_ramp() {
    let angle = 60f32.to_radians();
    let (level, _) = ramp_level(60.0, 2.0, 0.0);
    // Start resting on the slope at z = 1.2: the sphere's centre is one radius plus skin
    // off the slope along its normal (0, cos, −sin).
    let n = Vec3::new(0.0, angle.cos(), -angle.sin());
    let surface = Vec3::new(0.0, 1.2 * angle.tan(), 1.2);
    let sphere = surface + n * (CAPSULE.radius + 0.01);
    let mut w = Walker::standing_at(0.0, 0.0, 0.0);
    w.pos = sphere + Vec3::Y * CAPSULE.half_height;
    let start = w.pos;
    let mut slid = 0;
    for _ in 0..30 {
        let m = w.step(&level, Vec3::ZERO, DT);
        assert!(w.penetration(&level) < 1e-3);
        if m.sliding {
            slid += 1;
            assert!(!m.grounded);
        }
    }
    assert!(slid >= 20, "sliding on {slid} of 30 frames");
    let moved = w.pos - start;
    let downhill = Vec3::new(0.0, -angle.sin(), -angle.cos());
    assert!(moved.length() > 0.2, "moved only {moved}");
    let off = moved.normalize().angle_between(downhill).to_degrees();
    assert!(off < 5.0, "moved {moved}, {off}° off the slope line");
}

#[test]
fn diagonal_motion_into_a_wall_keeps_exactly_the_tangent_part() {
    for yaw_deg in [0.0f32, 30.0, -50.0] {
        let yaw = Quat::from_rotation_y(yaw_deg.to_radians());
        // A wall whose face (normal −x before turning) passes through the origin.
        let wall = LevelCollider::new(
            "wall",
            LevelShape::Box {
                half_extents: Vec3::new(0.5, 3.0, 20.0),
            },
            yaw * Vec3::new(0.5, 0.0, 0.0),
        )
        .rotated(yaw);
        let level = Level::new(vec![wall]).unwrap();
        let n = yaw * Vec3::NEG_X;
        let settings = ControllerSettings::default();
        // Touch the wall first.
        let mut pos = n * 0.5;
        let m = settings
            .move_shape(&level, &CAPSULE, &Transform::from_translation(pos), -n, DT)
            .unwrap();
        pos += m.translation;
        let gap = pos.dot(n) - CAPSULE.radius;
        assert!((gap - settings.skin).abs() < 1e-4, "gap {gap}");
        // Then move diagonally into it: what is kept is d − n(d·n).
        for d in [
            yaw * Vec3::new(0.2, 0.0, 0.2),
            yaw * Vec3::new(0.05, 0.03, -0.3),
            yaw * Vec3::new(1.0, -0.2, 0.1),
        ] {
            let m = settings
                .move_shape(&level, &CAPSULE, &Transform::from_translation(pos), d, DT)
                .unwrap();
            let tangent = d - n * d.dot(n);
            assert!(
                m.translation.abs_diff_eq(tangent, 1e-5),
                "yaw {yaw_deg}: moved {} for {d}, tangent part {tangent}",
                m.translation
            );
            assert_eq!(m.hits.len(), 1);
            assert!(m.hits[0].normal.abs_diff_eq(n, 1e-3));
        }
    }
}

#[test]
fn comes_to_rest_in_a_corner_without_jitter() {
    let level = Level::new(vec![
        floor(),
        block(
            "wall x",
            Vec3::new(1.0, 0.0, -5.0),
            Vec3::new(2.0, 3.0, 5.0),
        ),
        block(
            "wall z",
            Vec3::new(-5.0, 0.0, 1.0),
            Vec3::new(5.0, 3.0, 2.0),
        ),
    ])
    .unwrap();
    let mut w = Walker::standing_at(0.0, 0.01, 0.0);
    let push = Vec3::new(2.0, 0.0, 2.0);
    for _ in 0..60 {
        w.step(&level, push, DT);
    }
    let skin = w.settings.skin;
    let rest = 1.0 - CAPSULE.radius - skin;
    assert!(
        (w.pos.x - rest).abs() < 1e-3 && (w.pos.z - rest).abs() < 1e-3,
        "{}",
        w.pos
    );
    for f in 0..120 {
        let before = w.pos;
        let m = w.step(&level, push, DT);
        let change = (w.pos - before).length();
        assert!(change < 1e-4, "frame {f}: moved {change} m in the corner");
        assert!(m.grounded);
    }
}

#[test]
fn fifty_metres_per_second_never_pass_a_5_cm_wall() {
    for dt in [1.0 / 30.0, DT, 1.0 / 144.0] {
        for (offset, heading) in [
            (0.0f32, Vec3::X),
            (0.37, Vec3::new(1.0, 0.0, 0.3).normalize()),
            (-0.8, Vec3::new(1.0, 0.0, -0.6).normalize()),
        ] {
            let level = Level::new(vec![
                floor(),
                block(
                    "thin wall",
                    Vec3::new(3.0, 0.0, -100.0),
                    Vec3::new(3.05, 3.0, 100.0),
                ),
            ])
            .unwrap();
            let mut w = Walker::standing_at(0.0, 0.01, offset);
            for _ in 0..(1.0 / dt) as usize {
                w.step(&level, heading * 50.0, dt);
                assert!(
                    w.pos.x + CAPSULE.radius <= 3.0 + 1e-4,
                    "dt {dt}: through the wall at {}",
                    w.pos
                );
            }
            assert!(w.pos.x + CAPSULE.radius > 2.95, "stopped early: {}", w.pos);
        }
    }
}

#[test]
fn starting_inside_a_box_is_out_within_one_call() {
    let settings = ControllerSettings::default();
    let cases = [
        // 5 cm into the floor: pushed up by 5 cm and the skin.
        (
            vec![floor()],
            Vec3::new(0.0, HALF - 0.05, 0.0),
            Vec3::new(0.0, 0.06, 0.0),
        ),
        // 5 cm into a wall from the side.
        (
            vec![block(
                "wall",
                Vec3::new(1.0, -1.0, -5.0),
                Vec3::new(3.0, 3.0, 5.0),
            )],
            Vec3::new(1.0 - CAPSULE.radius + 0.05, 1.0, 0.0),
            Vec3::new(-0.06, 0.0, 0.0),
        ),
        // 5 cm into both the floor and a wall.
        (
            vec![
                floor(),
                block("wall", Vec3::new(1.0, 0.0, -5.0), Vec3::new(3.0, 3.0, 5.0)),
            ],
            Vec3::new(1.0 - CAPSULE.radius + 0.05, HALF - 0.05, 0.0),
            Vec3::new(-0.06, 0.06, 0.0),
        ),
    ];
    for (colliders, pos, expected) in cases {
        let level = Level::new(colliders).unwrap();
        let before =
            level.capsule_penetration(CAPSULE.radius, CAPSULE.half_height, pos, Quat::IDENTITY);
        assert!((before - 0.05).abs() < 1e-3, "set-up is {before} m deep");
        let m = settings
            .move_shape(
                &level,
                &CAPSULE,
                &Transform::from_translation(pos),
                Vec3::ZERO,
                DT,
            )
            .unwrap();
        let after = pos + m.translation;
        let depth =
            level.capsule_penetration(CAPSULE.radius, CAPSULE.half_height, after, Quat::IDENTITY);
        assert!(depth < 1e-4, "still {depth} m inside at {after}");
        // Out by the depth plus the skin, along the faces' normals.
        assert!(
            m.depenetration.abs_diff_eq(expected, 1e-4),
            "pushed {} instead of {expected}",
            m.depenetration
        );
    }
}

#[test]
fn walking_down_stairs_stays_grounded_on_every_frame() {
    // Five 0.2 m steps going down along +x: the top at 1 m from x = −2 to 0, then treads
    // 0.3 m deep, then the floor.
    let mut colliders = vec![floor()];
    colliders.push(block(
        "top",
        Vec3::new(-3.0, 0.0, -2.0),
        Vec3::new(0.0, 1.0, 2.0),
    ));
    for i in 0..4 {
        let x0 = i as f32 * 0.3;
        colliders.push(block(
            &format!("step {i}"),
            Vec3::new(x0, 0.0, -2.0),
            Vec3::new(x0 + 0.3, 0.8 - i as f32 * 0.2, 2.0),
        ));
    }
    let level = Level::new(colliders).unwrap();
    for speed in [1.4f32, 4.0] {
        let mut w = Walker::standing_at(-1.0, 1.01, 0.0);
        w.grounded = true;
        let mut snapped = 0;
        for f in 0..(3.0 / speed / DT) as usize {
            let m = w.step(&level, Vec3::new(speed, 0.0, 0.0), DT);
            assert!(
                m.grounded,
                "speed {speed}, frame {f}: airborne at {}",
                w.pos
            );
            assert!(w.penetration(&level) < 1e-3);
            snapped += m.snapped as usize;
        }
        assert!(w.pos.x > 1.5, "did not get down: {}", w.pos);
        assert!(
            (w.bottom() - w.settings.skin).abs() < 2e-3,
            "ends at {}",
            w.bottom()
        );
        assert!(snapped > 0);
    }
}

/// Issue 18: walking down stairs, the skin correction after snapping pushed out along the
/// upper step's rounded edge normal, which points forward: the character gained speed
/// (+13 % on two frames per step). Walking down must never go faster than the input.
#[test]
fn walking_down_stairs_never_gains_speed() {
    // Five 0.2 m steps down along +z: the top at 1 m up to z = 2, treads 0.3 m deep.
    let mut colliders = vec![floor()];
    colliders.push(block(
        "top",
        Vec3::new(-2.0, 0.0, -3.0),
        Vec3::new(2.0, 1.0, 2.0),
    ));
    for i in 0..4 {
        let z0 = 2.0 + i as f32 * 0.3;
        colliders.push(block(
            &format!("step {i}"),
            Vec3::new(-2.0, 0.0, z0),
            Vec3::new(2.0, 0.8 - i as f32 * 0.2, z0 + 0.3),
        ));
    }
    let level = Level::new(colliders).unwrap();
    for speed in [1.4f32, 2.5, 4.0] {
        let mut w = Walker::standing_at(0.0, 1.01, 1.0);
        w.grounded = true;
        let start = w.pos.z;
        let frames = (3.0 / speed / DT) as usize;
        for f in 0..frames {
            let m = w.step(&level, Vec3::new(0.0, 0.0, speed), DT);
            assert!(
                m.translation.z <= speed * DT * (1.0 + 1e-4),
                "speed {speed}, frame {f} at {}: moved {} m forward, the input is {} m",
                w.pos,
                m.translation.z,
                speed * DT
            );
            assert!(
                m.translation.x.abs() < 1e-5,
                "drifted sideways: {}",
                m.translation
            );
        }
        let travelled = w.pos.z - start;
        assert!(
            travelled <= frames as f32 * speed * DT + 1e-4,
            "speed {speed}: {travelled} m in {frames} frames"
        );
        assert!(w.pos.z > 3.5, "did not get down: {}", w.pos);
    }
}

#[test]
fn same_inputs_same_bits() {
    let mut colliders = vec![floor()];
    colliders.extend(stairs(1.0, 5, 0.2, 0.3));
    colliders.push(block(
        "wall",
        Vec3::new(-5.0, 0.0, 1.0),
        Vec3::new(5.0, 3.0, 2.0),
    ));
    let level = Level::new(colliders).unwrap();
    let run = || {
        let mut w = Walker::standing_at(0.0, 0.5, 0.0);
        let mut trace = Vec::new();
        for f in 0..200 {
            let a = f as f32 * 0.05;
            w.step(&level, Vec3::new(1.5 + a.sin(), 0.0, 1.0 + a.cos()), DT);
            trace.push(w.pos.to_array().map(f32::to_bits));
        }
        trace
    };
    assert_eq!(run(), run());
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let level = Level::new(vec![floor()]).unwrap();
    let s = ControllerSettings::default();
    let pose = Transform::from_translation(Vec3::new(0.0, 1.0, 0.0));
    let err = |r: tassel::Result<Movement>| r.unwrap_err().to_string();
    assert!(err(s.move_shape(&level, &CAPSULE, &pose, Vec3::NAN, DT)).contains("desired"));
    assert!(err(s.move_shape(&level, &CAPSULE, &pose, Vec3::ZERO, -1.0)).contains("time step"));
    assert!(err(s.move_shape(&level, &CAPSULE, &pose, Vec3::ZERO, f32::NAN)).contains("time step"));
    let bad_capsule = CharacterCapsule {
        radius: -0.3,
        half_height: 0.6,
    };
    assert!(err(s.move_shape(&level, &bad_capsule, &pose, Vec3::ZERO, DT)).contains("radius"));
    let bad_pose = Transform::from_translation(Vec3::new(f32::INFINITY, 0.0, 0.0));
    assert!(err(s.move_shape(&level, &CAPSULE, &bad_pose, Vec3::ZERO, DT)).contains("pose"));
    let bad = ControllerSettings {
        max_climb_angle: 120.0,
        ..s
    };
    assert!(
        err(bad.move_shape(&level, &CAPSULE, &pose, Vec3::ZERO, DT)).contains("max_climb_angle")
    );
    let bad = ControllerSettings { skin: -0.1, ..s };
    assert!(err(bad.move_shape(&level, &CAPSULE, &pose, Vec3::ZERO, DT)).contains("skin"));

    // Level errors name the collider.
    let e = Level::new(vec![LevelCollider::new(
        "crate",
        LevelShape::Box {
            half_extents: Vec3::new(1.0, -1.0, 1.0),
        },
        Vec3::ZERO,
    )])
    .unwrap_err()
    .to_string();
    assert!(e.contains("crate") && e.contains("half extents"), "{e}");
    let e = Level::new(vec![LevelCollider::new(
        "rock",
        LevelShape::TriMesh {
            vertices: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            indices: vec![[0, 1, 7]],
        },
        Vec3::ZERO,
    )])
    .unwrap_err()
    .to_string();
    assert!(e.contains("rock") && e.contains("vertex 7"), "{e}");

    // A huge time step with gravity: a fall of kilometres still lands on the floor.
    let m = s
        .move_shape(&level, &CAPSULE, &pose, Vec3::new(3.0, -1e6, 1.0), 1e3)
        .unwrap();
    let end = pose.translation + m.translation;
    assert!(end.is_finite() && end.y - HALF >= -1e-4, "{end}");
    assert!(m.grounded);
}

#[test]
fn a_jump_leaves_the_ground_and_lands() {
    let level = Level::new(vec![floor()]).unwrap();
    let mut w = Walker::standing_at(0.0, 0.01, 0.0);
    w.grounded = true;
    w.step(&level, Vec3::ZERO, DT);
    // Take-off at 4 m/s: by hand the apex is v²/2g = 0.815 m, the flight 2v/g = 0.815 s.
    w.vy = 4.0;
    w.grounded = false;
    let mut apex = 0.0f32;
    let mut air = 0;
    loop {
        let m = w.step(&level, Vec3::new(1.0, 0.0, 0.0), DT);
        apex = apex.max(w.bottom());
        if m.grounded {
            break;
        }
        air += 1;
        assert!(air < 200, "never landed");
        assert!(!m.snapped, "snapped while moving up or in the air");
    }
    assert!((apex - 0.815).abs() < 0.05, "apex {apex}");
    let flight = air as f32 * DT;
    assert!((flight - 0.815).abs() < 3.0 * DT, "flight {flight} s");
}

/// The seed's lift–sweep–drop: a thin capsule (radius 0.15 m) meets a 0.25 m riser with
/// its straight side, so only the step procedure can get it up; a ledge narrower than
/// `min_step_width` in front of a tall wall is refused.
#[test]
fn lift_sweep_drop_climbs_a_riser_met_with_the_straight_side() {
    const THIN: CharacterCapsule = CharacterCapsule {
        radius: 0.15,
        half_height: 0.75,
    };
    let run = |colliders: Vec<LevelCollider>| {
        let level = Level::new(colliders).unwrap();
        let s = ControllerSettings::default();
        let mut pos = Vec3::new(0.0, 0.9 + s.skin, 0.0);
        let (mut vy, mut stepped) = (0.0f32, 0);
        for _ in 0..90 {
            vy -= G * DT;
            let desired = Vec3::new(1.5 * DT, vy * DT, 0.0);
            let m = s
                .move_shape(
                    &level,
                    &THIN,
                    &Transform::from_translation(pos),
                    desired,
                    DT,
                )
                .unwrap();
            pos += m.translation;
            if m.grounded {
                vy = 0.0;
            }
            stepped += m.stepped as usize;
            let depth =
                level.capsule_penetration(THIN.radius, THIN.half_height, pos, Quat::IDENTITY);
            assert!(depth < 1e-3, "inside at {pos}");
        }
        (pos, stepped)
    };
    let (pos, stepped) = run(vec![
        floor(),
        block("step", Vec3::new(1.0, 0.0, -2.0), Vec3::new(4.0, 0.25, 2.0)),
    ]);
    assert!(stepped > 0);
    assert!(pos.x > 2.0, "{pos}");
    assert!(
        (pos.y - 0.9 - 0.25 - 0.01).abs() < 2e-3,
        "on the step? {pos}"
    );

    // The same riser with only 5 cm of ledge before a 2 m wall: no room to stand.
    let (pos, _) = run(vec![
        floor(),
        block("step", Vec3::new(1.0, 0.0, -2.0), Vec3::new(4.0, 0.25, 2.0)),
        block("wall", Vec3::new(1.05, 0.0, -2.0), Vec3::new(4.0, 2.0, 2.0)),
    ]);
    assert!(pos.y < 0.9 + 0.02, "climbed onto a 5 cm ledge: {pos}");
    assert!(pos.x + THIN.radius <= 1.0 + 1e-4, "{pos}");
}

/// The demo's run through its level (`tassel demo`): up the stairs onto the 0.9 m
/// platform, down the ramp, over the crate, along the wall (facing along it, not where
/// the input pushes), through the door while it is open, then carried and turned by the
/// moving platform; never inside anything, the door and the platform where they are on
/// each frame.
#[test]
fn the_demo_run_climbs_jumps_slides_and_rides_through_its_level() {
    use tassel::builtin::level::{moving_colliders, LevelRun, CRATE, DOOR, PLATFORM, STAIRS};
    use tassel::builtin::{self, DemoScript};
    let c = builtin::character();
    let mut animator = DemoScript.animator(&c);
    let mut run = LevelRun::new().unwrap();
    let mut locals = c.skeleton.rest().to_vec();
    let frames = (LevelRun::DURATION / DT).round() as usize;
    let (count, rise, tread, z0) = STAIRS;
    let top = count as f32 * rise;
    // The platform past the last stair runs 3.5 m.
    let platform = z0 + count as f32 * tread + 0.5..z0 + count as f32 * tread + 3.0;
    let (mut on_platform, mut states) = (0, Vec::new());
    let mut through_door = false;
    // The feet in the moving platform's frame, from the frame the ride starts.
    let mut on_ride: Option<Vec3> = None;
    let (mut ride_frames, mut ride_drift) = (0, 0.0f32);
    let mut facing_at_ride = Quat::IDENTITY;
    let mut end = Transform::IDENTITY;
    for f in 0..=frames {
        let t = f as f32 * DT;
        let m = run
            .frame(
                &c,
                &mut animator,
                t,
                if f == 0 { 0.0 } else { DT },
                &mut locals,
            )
            .unwrap();
        let feet = m.component.translation;
        end = m.component;
        if platform.contains(&feet.z) && t < 8.0 {
            on_platform += 1;
            assert!(
                (feet.y - top).abs() < 2e-3,
                "t = {t}: feet at {feet} on the platform"
            );
        }
        let name = animator.machine().state_name(m.state).to_string();
        if states.last() != Some(&name) {
            states.push(name);
        }
        let centre = feet + Vec3::Y * (run.capsule.half_total_height() + run.settings.skin);
        let depth = run.level.capsule_penetration(
            run.capsule.radius,
            run.capsule.half_height,
            centre,
            Quat::IDENTITY,
        );
        assert!(depth < 1e-3, "t = {t}: {depth} m inside at {feet}");
        // Over the crate the feet are above its top.
        if (CRATE.0..CRATE.0 + 0.6).contains(&feet.z) {
            assert!(feet.y > CRATE.1, "t = {t}: feet at {feet} over the crate");
        }
        // Sliding along the wall (pressed to it, the input 45° into it): it faces along
        // the wall within 2°, i.e. where it goes.
        if (9.6..10.6).contains(&t) {
            let x = 1.2 - run.capsule.radius - run.settings.skin;
            assert!((feet.x - x).abs() < 1e-3, "t = {t}: off the wall at {feet}");
            let forward = m.component.rotation * Vec3::Z;
            assert!(
                forward.angle_between(Vec3::Z) < 2f32.to_radians(),
                "t = {t}: faces {forward} while sliding along +z"
            );
        }
        // In the door's plane only while it is open (its bottom above the head).
        if (DOOR.0..DOOR.0 + DOOR.1).contains(&feet.z) {
            through_door = true;
            let (_, door, _) = moving_colliders(t)[0];
            assert!(door.y - 0.5 * DOOR.2 > 1.8, "t = {t}: under a closed door");
        }
        // The ride (the platform moves from 14.8 s to 17.8 s): the feet keep their place
        // on the platform within 1 mm, and the facing turns with it.
        let (_, p, r) = moving_colliders(t)[1];
        let local = r.inverse() * (feet - p);
        if t >= 14.7 {
            match on_ride {
                None => {
                    on_ride = Some(local);
                    facing_at_ride = m.component.rotation;
                    assert!(
                        (local.y - PLATFORM.1.y).abs() < 2e-3,
                        "t = {t}: not on the platform: {local}"
                    );
                }
                Some(first) => {
                    ride_frames += 1;
                    ride_drift = ride_drift.max((local - first).length());
                }
            }
        }
    }
    assert!(on_platform > 10, "{on_platform} frames on the platform");
    assert!(
        states.iter().any(|s| s.starts_with("jump_loop")),
        "{states:?}"
    );
    assert!(through_door, "never went through the door");
    assert!(ride_frames > 200);
    assert!(ride_drift < 1e-3, "slid {ride_drift} m on the platform");
    // The platform turned a quarter turn; so did the character.
    let turned = end.rotation * facing_at_ride.inverse();
    let (axis, angle) = turned.to_axis_angle();
    assert!(
        (angle - 90f32.to_radians()).abs() < 0.5f32.to_radians() && axis.y > 0.999,
        "turned {}° about {axis}",
        angle.to_degrees()
    );
    assert!(run.last.grounded);
}
