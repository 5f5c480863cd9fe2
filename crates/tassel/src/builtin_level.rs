//! The demo's small level and the run through it: the character controller moves the
//! built-in character's capsule from player-like input (speed, heading, a jump button);
//! the locomotion state machine is fed the controller's result (speed, jumping, landing).

use crate::anim::Animator;
use crate::controller::{
    CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape, Movement,
};
use crate::math::Transform;
use crate::rng::SplitMix64;
use glam::{Quat, Vec3};

use super::Character;

fn block(name: &str, min: Vec3, max: Vec3) -> LevelCollider {
    LevelCollider::new(
        name,
        LevelShape::Box {
            half_extents: (max - min) * 0.5,
        },
        (max + min) * 0.5,
    )
}

/// Stair steps of the demo: count, rise and tread (m), first riser at z.
pub const STAIRS: (usize, f32, f32, f32) = (5, 0.18, 0.35, 4.5);
/// The crate jumped over: its near face (z) and height (m).
pub const CRATE: (f32, f32) = (20.0, 0.35);

/// The door at the wall's end: a slab across the path (x from −1.5 m to the wall's face,
/// z from 28.5 m, 0.15 m thick, 2.3 m high) that rises 2.4 m to let the character through
/// and comes down behind it.
pub const DOOR: (f32, f32, f32) = (28.5, 0.15, 2.3);
/// The moving platform: a 2.4 m × 2.4 m slab whose top is 0.15 m above the floor,
/// centred at x = 0.5 m, z = 31.5 m when the character steps on. It carries the character
/// 2.5 m to the side and 2.5 m on while it turns a quarter turn.
pub const PLATFORM: (Vec3, Vec3) = (Vec3::new(0.5, 0.075, 31.5), Vec3::new(1.2, 0.075, 1.2));

/// Seconds when the door opens and closes (each over [`DOOR_TRAVEL`]) and the platform's
/// ride (start, end).
const DOOR_OPEN: f32 = 10.6;
const DOOR_CLOSE: f32 = 13.8;
const DOOR_TRAVEL: f32 = 0.8;
const RIDE: (f32, f32) = (14.8, 17.8);

/// 0 → 1 with zero speed at both ends, for `x` from 0 to 1 (clamped).
fn smoothstep(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// The poses at time `t` (seconds into the run) of the demo level's colliders that move,
/// by name: `"door"` (rises, then comes down) and `"platform"` (carries the character aside
/// while it turns 90°). At `t = 0` these are their poses in [`demo_level`].
pub fn moving_colliders(t: f32) -> [(&'static str, Vec3, Quat); 2] {
    let (z, thick, high) = DOOR;
    let open =
        smoothstep((t - DOOR_OPEN) / DOOR_TRAVEL) - smoothstep((t - DOOR_CLOSE) / DOOR_TRAVEL);
    let door = Vec3::new(-0.15, 0.5 * high + 2.4 * open, z + 0.5 * thick);
    let ride = smoothstep((t - RIDE.0) / (RIDE.1 - RIDE.0));
    let platform = PLATFORM.0 + Vec3::new(-2.5, 0.0, 2.5) * ride;
    [
        ("door", door, Quat::IDENTITY),
        (
            "platform",
            platform,
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2 * ride),
        ),
    ]
}

/// The demo level along +z: floor; five 0.18 m stairs up to a 0.9 m platform; a 20° ramp
/// back down; a crate to jump over; a wall at x = 1.2 m to slide along; a door at its end
/// that opens and closes, and a moving platform past it (their motion:
/// [`moving_colliders`]); a boulder (sphere), a pillar (capsule) and a rock (triangle
/// mesh) beside the path.
pub fn demo_level() -> Vec<LevelCollider> {
    let (count, rise, tread, z0) = STAIRS;
    let top = count as f32 * rise;
    let platform_end = z0 + count as f32 * tread + 3.5;
    let mut c = vec![block(
        "floor",
        Vec3::new(-20.0, -1.0, -10.0),
        Vec3::new(20.0, 0.0, 60.0),
    )];
    for i in 0..count {
        let z = z0 + i as f32 * tread;
        c.push(block(
            &format!("stair {i}"),
            Vec3::new(-1.5, 0.0, z),
            Vec3::new(1.0, (i + 1) as f32 * rise, platform_end),
        ));
    }
    // A ramp down: the wedge turned to face back, its high edge against the platform.
    let angle = 20f32.to_radians();
    let run = top / angle.tan();
    c.push(
        LevelCollider::new(
            "ramp",
            LevelShape::Ramp {
                width: 2.5,
                length: run,
                height: top,
            },
            Vec3::new(-0.25, 0.0, platform_end + run),
        )
        .rotated(Quat::from_rotation_y(std::f32::consts::PI)),
    );
    c.push(block(
        "crate",
        Vec3::new(-1.0, 0.0, CRATE.0),
        Vec3::new(1.0, CRATE.1, CRATE.0 + 0.6),
    ));
    c.push(block(
        "wall",
        Vec3::new(1.2, 0.0, 21.0),
        Vec3::new(1.5, 2.5, DOOR.0 + DOOR.1),
    ));
    for (name, position, rotation) in moving_colliders(0.0) {
        let half_extents = match name {
            "door" => Vec3::new(1.35, 0.5 * DOOR.2, 0.5 * DOOR.1),
            _ => PLATFORM.1,
        };
        c.push(
            LevelCollider::new(name, LevelShape::Box { half_extents }, position).rotated(rotation),
        );
    }
    c.push(LevelCollider::new(
        "boulder",
        LevelShape::Sphere { radius: 0.8 },
        Vec3::new(-4.0, 0.3, 8.0),
    ));
    c.push(LevelCollider::new(
        "pillar",
        LevelShape::Capsule {
            half_height: 1.2,
            radius: 0.3,
        },
        Vec3::new(-3.0, 1.5, 14.0),
    ));
    // A four-sided rock as a triangle mesh.
    c.push(LevelCollider::new(
        "rock",
        LevelShape::TriMesh {
            vertices: vec![
                Vec3::new(-0.8, 0.0, -0.8),
                Vec3::new(0.8, 0.0, -0.8),
                Vec3::new(0.8, 0.0, 0.8),
                Vec3::new(-0.8, 0.0, 0.8),
                Vec3::new(0.0, 0.7, 0.0),
            ],
            indices: vec![[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]],
        },
        Vec3::new(-3.5, 0.0, 18.0),
    ));
    c
}

/// A level of `count` colliders for benchmarks: the demo level plus seeded boxes, spheres
/// and capsules scattered over 200 m × 200 m away from the path (x ∈ [−2, 2]).
pub fn bench_level(count: usize, seed: u64) -> Vec<LevelCollider> {
    let mut c = demo_level();
    let mut rng = SplitMix64::new(seed);
    let mut i = 0;
    while c.len() < count {
        let mut x = rng.range_f32(-100.0, 100.0);
        if x.abs() < 4.0 {
            x += 8.0f32.copysign(x);
        }
        let z = rng.range_f32(-100.0, 100.0);
        let size = rng.range_f32(0.2, 1.5);
        let shape = match i % 3 {
            0 => LevelShape::Box {
                half_extents: Vec3::new(size, rng.range_f32(0.2, 2.0), size * 0.7),
            },
            1 => LevelShape::Sphere { radius: size },
            _ => LevelShape::Capsule {
                half_height: size,
                radius: 0.3 * size,
            },
        };
        let yaw = rng.range_f32(0.0, std::f32::consts::TAU);
        c.push(
            LevelCollider::new(format!("scatter {i}"), shape, Vec3::new(x, 0.5 * size, z))
                .rotated(Quat::from_rotation_y(yaw)),
        );
        i += 1;
    }
    c
}

/// The controller benchmark's three moves in a level built from [`bench_level`] (or
/// [`demo_level`]), for the demo's capsule (1.7 m, radius 0.28 m) and default settings,
/// one 60 Hz frame each with one frame of gravity: `(name, capsule pose, desired)` for a
/// walk (1.4 m/s) on flat ground, a walk at 45° into the wall (touching its near face),
/// and a walk that climbs the first stair riser, its pose found by walking up to the
/// stairs. Errors if that walk never climbs the riser.
pub fn bench_moves(level: &Level) -> crate::Result<[(&'static str, Transform, Vec3); 3]> {
    let capsule = CharacterCapsule::with_height(1.7, 0.28);
    let s = ControllerSettings::default();
    let dt = 1.0 / 60.0;
    let centre_y = capsule.half_total_height() + s.skin;
    let walk = Vec3::new(0.0, -GRAVITY * dt * dt, 1.4 * dt);
    let flat = Transform::from_translation(Vec3::new(0.0, centre_y, 1.0));
    let at_wall = Transform::from_translation(Vec3::new(1.2 - 0.28 - s.skin, centre_y, 25.0));
    let diagonal = Vec3::new(1.0, 0.0, 1.0).normalize() * 1.4 * dt + Vec3::new(0.0, walk.y, 0.0);
    let mut pose = Transform::from_translation(Vec3::new(0.0, centre_y, STAIRS.3 - 0.6));
    let before_step = loop {
        let m = s.move_shape(level, &capsule, &pose, walk, dt)?;
        if m.stepped {
            break pose;
        }
        pose.translation += m.translation;
        if pose.translation.z >= STAIRS.3 + 0.5 {
            return Err(crate::Error::InvalidParameter(
                "the bench walk never climbed the first stair riser".into(),
            ));
        }
    };
    Ok([
        ("walk_flat", flat, walk),
        ("walk_into_wall", at_wall, diagonal),
        ("walk_up_stairs", before_step, walk),
    ])
}

/// Player input over time: `(start s, speed m/s, heading degrees from +z towards +x,
/// label)`.
const INPUT: [(f32, f32, f32, &str); 8] = [
    (0.0, 0.0, 0.0, "idle"),
    (1.0, 1.4, 0.0, "walk"),
    (3.2, 4.0, 0.0, "run: stairs, ramp"),
    (6.3, 4.0, 0.0, "jump the crate"),
    (8.4, 1.4, 45.0, "slide along wall"),
    (10.6, 1.4, 0.0, "through the door"),
    (14.4, 0.0, 0.0, "ride the platform"),
    (17.9, 0.0, 0.0, "idle"),
];

/// The demo's gust while the character rides the platform: a `curve` external force in
/// world space (across the platform and a little forward), rising for 0.9 s and dying
/// away by 1.6 s, on every chain; off until [`GUST_EVENTS`] turn it on.
pub fn gust() -> crate::dynamics::chain::ExternalForceSettings {
    use crate::dynamics::chain::{ExternalForceSettings, ForceKind};
    ExternalForceSettings {
        name: "gust".into(),
        kind: ForceKind::Curve,
        enabled: false,
        force_curve: vec![
            [0.0, 0.0, 0.0, 0.0],
            [0.9, 0.35, 0.05, 0.12],
            [1.6, 0.0, 0.0, 0.0],
        ],
        random_force_scale_range: [0.8, 1.2],
        seed: 15,
        ..Default::default()
    }
}

/// When the demo's animation events turn the gust on and off (seconds, event).
pub const GUST_EVENTS: [(f32, &str); 2] = [
    (15.4, "tassel:enable_force gust"),
    (17.0, "tassel:disable_force gust"),
];

/// The jump button is pressed at this time (while running).
const JUMP_AT: f32 = 6.3;
/// Take-off speed, m/s (apex v²/2g ≈ 0.8 m).
const TAKE_OFF: f32 = 4.0;
/// Gravity, m/s².
const GRAVITY: f32 = 9.81;
/// How fast the character turns to face where it goes, rad/s (a quarter turn in 0.2 s).
const FACING_RATE: f32 = 8.0;

/// `a` brought into `(-π, π]`.
fn wrap_angle(a: f32) -> f32 {
    let r = a.rem_euclid(std::f32::consts::TAU);
    if r > std::f32::consts::PI {
        r - std::f32::consts::TAU
    } else {
        r
    }
}

/// The demo's run through [`demo_level`]: player input → controller → state machine.
pub struct LevelRun {
    /// The level.
    pub level: std::sync::Arc<Level>,
    /// The character's capsule (1.7 m, radius 0.28 m).
    pub capsule: CharacterCapsule,
    /// Controller settings (defaults).
    pub settings: ControllerSettings,
    centre: Vec3,
    /// Where the input moves the character (turns towards the heading).
    yaw: f32,
    /// Where the character faces: towards where it actually goes.
    facing: f32,
    /// The last move's horizontal distance over the input's (1 unless something deflected
    /// it): the state machine's speed is the input's times this.
    speed_scale: f32,
    /// Level ids of the colliders of [`moving_colliders`], in order.
    movers: [usize; 2],
    vy: f32,
    grounded: bool,
    jumping: bool,
    airborne: bool,
    /// The last movement.
    pub last: Movement,
}

/// What one frame of the run produced.
#[derive(Debug, Clone)]
pub struct RunFrame {
    /// The character's world transform (feet on the ground).
    pub component: Transform,
    /// The input phase.
    pub phase: &'static str,
    /// Input speed, m/s.
    pub speed: f32,
    /// The state machine's current state.
    pub state: usize,
    /// Events the state machine fired this frame.
    pub events: usize,
}

impl LevelRun {
    /// Length of the run, seconds.
    pub const DURATION: f32 = 18.5;

    /// The run at its start, standing on the floor.
    pub fn new() -> crate::Result<Self> {
        let capsule = CharacterCapsule::with_height(1.7, 0.28);
        let settings = ControllerSettings::default();
        let level = Level::new(demo_level())?;
        let id = |name: &str| {
            level
                .colliders()
                .find(|(_, c)| c.name == name)
                .map(|(id, _)| id)
                .ok_or_else(|| crate::Error::InvalidParameter(format!("no collider '{name}'")))
        };
        let [(a, ..), (b, ..)] = moving_colliders(0.0);
        let movers = [id(a)?, id(b)?];
        Ok(Self {
            level: std::sync::Arc::new(level),
            centre: Vec3::new(0.0, capsule.half_total_height() + settings.skin, 0.0),
            capsule,
            settings,
            yaw: 0.0,
            facing: 0.0,
            speed_scale: 1.0,
            movers,
            vy: 0.0,
            grounded: true,
            jumping: false,
            airborne: false,
            last: Movement::default(),
        })
    }

    /// The phases of the run: (start time, seconds; label), in order.
    pub fn phases() -> impl Iterator<Item = (f32, &'static str)> {
        INPUT.iter().map(|s| (s.0, s.3))
    }

    /// The input at `t`: (speed, heading radians, phase label).
    pub fn input(t: f32) -> (f32, f32, &'static str) {
        let s = INPUT
            .iter()
            .rev()
            .find(|s| t >= s.0)
            .copied()
            .unwrap_or(INPUT[0]);
        (s.1, s.2.to_radians(), s.3)
    }

    /// One frame: moves the door and the platform to their poses at `t` (in
    /// [`LevelRun::level`], copied first if someone else holds it), sets the state
    /// machine's parameters from the input and the controller's last result, advances
    /// `animator` into `locals`, then moves the capsule (gravity and the jump's take-off
    /// applied here, as a game would; a platform carries and turns it) and returns where
    /// the character is and where it faces (towards where it went, so that a wall that
    /// deflects it turns it along the wall). `dt = 0` (the first frame) only poses.
    pub fn frame(
        &mut self,
        c: &Character,
        animator: &mut Animator,
        t: f32,
        dt: f32,
        locals: &mut [Transform],
    ) -> crate::Result<RunFrame> {
        let (speed, heading, phase) = Self::input(t);
        let level = std::sync::Arc::make_mut(&mut self.level);
        level.start_frame();
        for (&id, (_, position, rotation)) in self.movers.iter().zip(moving_colliders(t)) {
            level.set_pose(id, position, rotation)?;
        }
        // The button is held from the press until the landing after take-off.
        if t >= JUMP_AT && !self.jumping && !self.airborne && self.grounded && t < JUMP_AT + 0.5 {
            self.jumping = true;
        }
        if let (Some(s), Some(j)) = (
            animator.machine().param("speed"),
            animator.machine().param("jumping"),
        ) {
            animator.state.set(s, speed * self.speed_scale);
            animator.state.set(j, if self.jumping { 1.0 } else { 0.0 });
        }
        let plan = animator.update(&c.clips, c.skeleton.rest(), dt, locals)?;
        let (state_index, events) = (plan.state, plan.events.len());
        let state = animator.machine().state_name(state_index);
        if self.jumping && !self.airborne && state.starts_with("jump_loop") {
            // The jump_start clip has ended: leave the ground.
            self.vy = TAKE_OFF;
            self.airborne = true;
        }
        if dt > 0.0 {
            // Turn towards the heading at up to 3 rad/s.
            let turn = (heading - self.yaw).clamp(-3.0 * dt, 3.0 * dt);
            self.yaw += turn;
            if self.grounded && !self.airborne {
                self.vy = 0.0;
            }
            self.vy -= GRAVITY * dt;
            let forward = Quat::from_rotation_y(self.yaw) * Vec3::Z;
            let desired = forward * speed * dt + Vec3::Y * self.vy * dt;
            // Into the last movement: its hit buffer is reused.
            let mut m = std::mem::take(&mut self.last);
            self.settings.move_shape_into(
                &self.level,
                &self.capsule,
                &Transform::from_translation(self.centre),
                desired,
                dt,
                &mut m,
            )?;
            self.centre += m.translation;
            self.grounded = m.grounded;
            // A platform turns both the way the input points and the facing.
            let spin = m.platform_rotation.to_scaled_axis().y;
            self.yaw += spin;
            self.facing += spin;
            // Face where the input took the character: the move less what carried it.
            let carried = match m.platform {
                Some(id) => self
                    .level
                    .motion(id)
                    .map(|(from, to)| {
                        let before = self.centre - m.translation;
                        (to * from.inverse()).transform_point(before) - before
                    })
                    .unwrap_or(Vec3::ZERO),
                None => Vec3::ZERO,
            };
            let own = m.translation - carried;
            let (went, wanted) = (
                Vec3::new(own.x, 0.0, own.z).length(),
                Vec3::new(desired.x, 0.0, desired.z).length(),
            );
            self.speed_scale = if wanted > 1e-6 {
                (went / wanted).min(1.0)
            } else {
                1.0
            };
            if speed > 0.0 && went > 0.3 * wanted && wanted > 1e-6 {
                let target = own.x.atan2(own.z);
                let delta = wrap_angle(target - self.facing);
                self.facing += delta.clamp(-FACING_RATE * dt, FACING_RATE * dt);
            }
            if m.grounded && self.vy <= 0.0 {
                self.vy = 0.0;
                if self.airborne {
                    self.airborne = false;
                    self.jumping = false;
                }
            } else if self.vy > 0.0 && m.translation.y < 0.5 * desired.y {
                // A ceiling stopped the rise.
                self.vy = 0.0;
            }
            self.last = m;
        }
        let feet = self.centre - Vec3::Y * (self.capsule.half_total_height() + self.settings.skin);
        Ok(RunFrame {
            component: Transform::from_translation_rotation(
                feet,
                Quat::from_rotation_y(self.facing),
            ),
            phase,
            speed,
            state: state_index,
            events,
        })
    }
}
