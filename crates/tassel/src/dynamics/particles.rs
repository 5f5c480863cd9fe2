//! A general particle-constraint world after the Verlet tutorial (seed 001): particles
//! with Verlet integration; sticks (distance constraints, rigid or soft), pins, angle
//! constraints; builders for a rope, a triangle, a tetrahedron and a cloth grid; ground,
//! sphere and capsule colliders; particles attached to bones so that a rope or a banner
//! can hang from a character.
//!
//! ```
//! use glam::Vec3;
//! use tassel::dynamics::particles::{ParticleWorld, ParticleSettings};
//! let mut w = ParticleWorld::new(ParticleSettings::default());
//! let rope = w.add_rope(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), 10, 1.0);
//! w.pin(rope[0], Vec3::ZERO).unwrap();
//! for _ in 0..60 { w.step(1.0 / 60.0).unwrap(); }
//! assert!(w.position(rope[9]).y < 0.0);
//! ```

use crate::collide::{PlacedCollider, Shape};
use crate::controller::Level;
use crate::dynamics::world::collide_points;
use crate::error::{Error, Result};
use crate::math::{normalize_or, Transform};
use crate::rng::SplitMix64;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// World-wide parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ParticleSettings {
    /// Gravity, m/s².
    pub gravity: Vec3,
    /// Velocity lost per step, 0..=1.
    pub damping: f32,
    /// Fixed step, seconds (0, 0.1].
    pub time_step: f32,
    /// Constraint iterations per step (≥ 1).
    pub iterations: u32,
    /// Collision radius of every particle, metres (≥ 0).
    pub radius: f32,
    /// Hitch guard: at most this many steps per call.
    pub max_steps_per_frame: u32,
    /// Share of the sliding velocity a particle loses on each contact step, 0..=1: the
    /// whole share when the contact pushed it out by at least gravity's push of one step
    /// (|gravity|·time_step²), proportionally less for a lighter touch.
    pub friction: f32,
    /// Wind as an acceleration, m/s² (world space).
    pub wind: Vec3,
    /// Gust amount 0..=1: each particle and step scales the wind by a random factor in
    /// `[1 − gust, 1 + gust]`.
    pub gust: f32,
    /// Seed of the gust generator.
    pub seed: u64,
}

impl Default for ParticleSettings {
    fn default() -> Self {
        Self {
            gravity: Vec3::new(0.0, -9.81, 0.0),
            damping: 0.01,
            time_step: 1.0 / 120.0,
            iterations: 8,
            radius: 0.0,
            max_steps_per_frame: 24,
            friction: 0.0,
            wind: Vec3::ZERO,
            gust: 0.0,
            seed: 1,
        }
    }
}

impl ParticleSettings {
    /// Checks every parameter, naming the first one out of range.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, v: String| {
            Err(Error::InvalidParameter(format!(
                "particle world: {name} = {v} is out of range"
            )))
        };
        if !self.gravity.is_finite() {
            return bad("gravity", format!("{}", self.gravity));
        }
        if !(0.0..=1.0).contains(&self.damping) {
            return bad("damping", format!("{} (0..=1)", self.damping));
        }
        let min_step = crate::limits::MIN_TIME_STEP;
        if !(self.time_step.is_finite() && self.time_step >= min_step && self.time_step <= 0.1) {
            return bad("time_step", format!("{} [{min_step}, 0.1]", self.time_step));
        }
        let max_iterations = crate::limits::MAX_ITERATIONS;
        if self.iterations == 0 || self.iterations > max_iterations {
            return bad(
                "iterations",
                format!("{} (1..={max_iterations})", self.iterations),
            );
        }
        if !(self.radius.is_finite() && self.radius >= 0.0) {
            return bad("radius", format!("{} (≥ 0)", self.radius));
        }
        let max_steps = crate::limits::MAX_STEPS_PER_FRAME;
        if !(1..=max_steps).contains(&self.max_steps_per_frame) {
            return bad(
                "max_steps_per_frame",
                format!("{} (1..={max_steps})", self.max_steps_per_frame),
            );
        }
        if !self.wind.is_finite() {
            return bad("wind", format!("{}", self.wind));
        }
        if !(0.0..=1.0).contains(&self.gust) {
            return bad("gust", format!("{} (0..=1)", self.gust));
        }
        if !(0.0..=1.0).contains(&self.friction) {
            return bad("friction", format!("{} (0..=1)", self.friction));
        }
        Ok(())
    }
}

/// A distance constraint. `stiffness` 1 is a rigid stick; below 1 a soft stick that only
/// corrects that fraction of the error per iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stick {
    /// First particle.
    pub a: usize,
    /// Second particle.
    pub b: usize,
    /// Rest length, metres.
    pub length: f32,
    /// 0..=1.
    pub stiffness: f32,
}

/// Keeps the angle at `center` between the arms to `a` and `b` within `[min, max]`
/// radians (it moves the arm ends, keeping their distances to the centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AngleConstraint {
    /// One arm's end.
    pub a: usize,
    /// The vertex.
    pub center: usize,
    /// The other arm's end.
    pub b: usize,
    /// Smallest angle, degrees.
    pub min: f32,
    /// Largest angle, degrees.
    pub max: f32,
}

/// The world: particles in structure-of-arrays buffers and their constraints.
#[derive(Debug, Clone)]
pub struct ParticleWorld {
    /// Parameters.
    pub settings: ParticleSettings,
    pos: Vec<Vec3>,
    prev: Vec<Vec3>,
    inv_mass: Vec<f32>,
    pin_target: Vec<Option<Vec3>>,
    contact: Vec<Vec3>,
    sticks: Vec<Stick>,
    angles: Vec<AngleConstraint>,
    /// Colliders (world space).
    pub colliders: Vec<PlacedCollider>,
    attachments: Vec<(usize, usize, Vec3)>,
    remaining: f32,
    rng: SplitMix64,
}

impl ParticleWorld {
    /// An empty world.
    pub fn new(settings: ParticleSettings) -> Self {
        Self {
            pos: Vec::new(),
            prev: Vec::new(),
            inv_mass: Vec::new(),
            pin_target: Vec::new(),
            contact: Vec::new(),
            sticks: Vec::new(),
            angles: Vec::new(),
            colliders: Vec::new(),
            attachments: Vec::new(),
            remaining: 0.0,
            rng: SplitMix64::new(settings.seed),
            settings,
        }
    }

    /// Adds a particle at rest with mass `mass` (kg, > 0). Returns its index.
    pub fn add_particle(&mut self, at: Vec3, mass: f32) -> usize {
        self.pos.push(at);
        self.prev.push(at);
        self.inv_mass.push(if mass > 0.0 && mass.is_finite() {
            1.0 / mass
        } else {
            1.0
        });
        self.pin_target.push(None);
        self.contact.push(Vec3::ZERO);
        self.pos.len() - 1
    }

    /// Number of particles.
    pub fn len(&self) -> usize {
        self.pos.len()
    }

    /// True without particles.
    pub fn is_empty(&self) -> bool {
        self.pos.is_empty()
    }

    /// Where particle `i` is.
    pub fn position(&self, i: usize) -> Vec3 {
        self.pos[i]
    }

    /// All positions.
    pub fn positions(&self) -> &[Vec3] {
        &self.pos
    }

    /// Moves particle `i` (and its previous position: no velocity is created).
    pub fn set_position(&mut self, i: usize, at: Vec3) {
        self.pos[i] = at;
        self.prev[i] = at;
    }

    fn check(&self, i: usize, what: &str) -> Result<()> {
        if i < self.pos.len() {
            Ok(())
        } else {
            Err(Error::InvalidParameter(format!(
                "{what}: particle {i} does not exist (the world has {})",
                self.pos.len()
            )))
        }
    }

    /// Gives particle `i` the velocity `v` (m/s) for the next step.
    pub fn set_velocity(&mut self, i: usize, v: Vec3) {
        self.prev[i] = self.pos[i] - v * self.settings.time_step;
    }

    /// Particle `i`'s velocity over the last step, m/s.
    pub fn velocity(&self, i: usize) -> Vec3 {
        (self.pos[i] - self.prev[i]) / self.settings.time_step
    }

    /// A rigid stick between `a` and `b` at their current distance.
    pub fn add_stick(&mut self, a: usize, b: usize) -> Result<()> {
        self.add_soft_stick(a, b, 1.0)
    }

    /// A soft stick at the current distance: `stiffness` (0..=1) is the share of the
    /// length error it corrects per iteration.
    pub fn add_soft_stick(&mut self, a: usize, b: usize, stiffness: f32) -> Result<()> {
        self.check(a, "stick")?;
        self.check(b, "stick")?;
        if !(0.0..=1.0).contains(&stiffness) {
            return Err(Error::InvalidParameter(format!(
                "stick {a}-{b}: stiffness {stiffness} is outside 0..=1"
            )));
        }
        self.push_stick(stiffness, a, b);
        Ok(())
    }

    /// A stick between existing particles (the builders' indices are valid by
    /// construction).
    fn push_stick(&mut self, stiffness: f32, a: usize, b: usize) {
        let length = (self.pos[a] - self.pos[b]).length();
        self.sticks.push(Stick {
            a,
            b,
            length,
            stiffness,
        });
    }

    /// Keeps the angle at `center` between the arms to `a` and `b` within
    /// `[min, max]` degrees (0 ≤ min ≤ max ≤ 180).
    pub fn add_angle_constraint(
        &mut self,
        a: usize,
        center: usize,
        b: usize,
        min: f32,
        max: f32,
    ) -> Result<()> {
        for i in [a, center, b] {
            self.check(i, "angle constraint")?;
        }
        if !(min >= 0.0 && min <= max && max <= 180.0) {
            return Err(Error::InvalidParameter(format!(
                "angle constraint at {center}: range [{min}, {max}] ° is not within [0, 180]"
            )));
        }
        self.angles.push(AngleConstraint {
            a,
            center,
            b,
            min,
            max,
        });
        Ok(())
    }

    /// The distance constraints.
    pub fn sticks(&self) -> &[Stick] {
        &self.sticks
    }

    /// The angle constraints.
    pub fn angle_constraints(&self) -> &[AngleConstraint] {
        &self.angles
    }

    /// Pins particle `i` at `at` (it no longer moves by itself).
    pub fn pin(&mut self, i: usize, at: Vec3) -> Result<()> {
        self.check(i, "pin")?;
        if !at.is_finite() {
            return Err(Error::InvalidParameter(format!(
                "pin of particle {i}: position {at} is not finite"
            )));
        }
        self.pin_target[i] = Some(at);
        self.set_position(i, at);
        Ok(())
    }

    /// Releases a pin (and a bone attachment).
    pub fn unpin(&mut self, i: usize) {
        if i < self.pos.len() {
            self.pin_target[i] = None;
            self.attachments.retain(|a| a.0 != i);
        }
    }

    /// Attaches particle `i` to bone `joint` at `offset` in the bone's space: it is pinned
    /// where it is now and, from the next [`ParticleWorld::follow_bones`] on, where the bone
    /// puts it.
    pub fn attach(&mut self, i: usize, joint: usize, offset: Vec3) -> Result<()> {
        self.check(i, "attach")?;
        if !offset.is_finite() {
            return Err(Error::InvalidParameter(format!(
                "attachment of particle {i}: offset {offset} is not finite"
            )));
        }
        self.pin_target[i] = Some(self.pos[i]);
        self.attachments.push((i, joint, offset));
        Ok(())
    }

    /// Moves the pins of attached particles to their bones (`models` in the character's
    /// space, `component` its world transform).
    pub fn follow_bones(&mut self, models: &[Transform], component: &Transform) -> Result<()> {
        for &(i, j, offset) in &self.attachments {
            let bone = models.get(j).ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "particle {i} is attached to joint {j}, which the pose lacks"
                ))
            })?;
            self.pin_target[i] = Some(component.transform_point(bone.transform_point(offset)));
        }
        Ok(())
    }

    /// A rope of `n` particles from `a` to `b` with sticks between neighbours; returns the
    /// particle indices. `mass` is the total mass.
    pub fn add_rope(&mut self, a: Vec3, b: Vec3, n: usize, mass: f32) -> Vec<usize> {
        let n = n.max(2);
        let ids: Vec<usize> = (0..n)
            .map(|k| self.add_particle(a.lerp(b, k as f32 / (n - 1) as f32), mass / n as f32))
            .collect();
        for w in ids.windows(2) {
            self.push_stick(1.0, w[0], w[1]);
        }
        ids
    }

    /// A triangle of three particles with three sticks.
    pub fn add_triangle(&mut self, p: [Vec3; 3], mass: f32) -> [usize; 3] {
        let ids = p.map(|q| self.add_particle(q, mass / 3.0));
        self.push_stick(1.0, ids[0], ids[1]);
        self.push_stick(1.0, ids[1], ids[2]);
        self.push_stick(1.0, ids[2], ids[0]);
        ids
    }

    /// A regular tetrahedron with edge `edge` centred at `center`: four particles, six
    /// sticks.
    pub fn add_tetrahedron(
        &mut self,
        center: Vec3,
        edge: f32,
        rotation: Quat,
        mass: f32,
    ) -> [usize; 4] {
        let s = edge / (2.0 * std::f32::consts::SQRT_2);
        let corners = [
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, -1.0, 1.0),
        ];
        let ids = corners.map(|c| self.add_particle(center + rotation * (c * s), mass / 4.0));
        for i in 0..4 {
            for j in i + 1..4 {
                self.push_stick(1.0, ids[i], ids[j]);
            }
        }
        ids
    }

    /// A cloth grid of `count = [nx, ny]` particles spanning `origin + u·[0,1] + v·[0,1]`, with
    /// horizontal and vertical sticks and, with `shear`, both diagonals. Returns indices
    /// row by row (`ids[y * nx + x]`).
    pub fn add_cloth(
        &mut self,
        origin: Vec3,
        u: Vec3,
        v: Vec3,
        count: [usize; 2],
        shear: bool,
        mass: f32,
    ) -> Vec<usize> {
        let (nx, ny) = (count[0].max(2), count[1].max(2));
        let m = mass / (nx * ny) as f32;
        let mut ids = Vec::with_capacity(nx * ny);
        for y in 0..ny {
            for x in 0..nx {
                let p =
                    origin + u * (x as f32 / (nx - 1) as f32) + v * (y as f32 / (ny - 1) as f32);
                ids.push(self.add_particle(p, m));
            }
        }
        for y in 0..ny {
            for x in 0..nx {
                let i = ids[y * nx + x];
                if x + 1 < nx {
                    self.push_stick(1.0, i, ids[y * nx + x + 1]);
                }
                if y + 1 < ny {
                    self.push_stick(1.0, i, ids[(y + 1) * nx + x]);
                }
                if shear && x + 1 < nx && y + 1 < ny {
                    self.push_stick(0.5, i, ids[(y + 1) * nx + x + 1]);
                    self.push_stick(0.5, ids[y * nx + x + 1], ids[(y + 1) * nx + x]);
                }
            }
        }
        ids
    }

    /// Adds a ground plane at `height` (world +Y up).
    pub fn add_ground(&mut self, height: f32) {
        self.colliders.push(PlacedCollider {
            shape: Shape::Plane,
            transform: Transform::from_translation(Vec3::Y * height),
        });
    }

    /// Advances by `dt` seconds in fixed steps (the remainder carried over).
    pub fn step(&mut self, dt: f32) -> Result<()> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidTimeStep(dt));
        }
        self.settings.validate()?;
        let s = &self.settings;
        let h = s.time_step;
        self.remaining += dt;
        let mut steps = (self.remaining / h + 1e-4).floor() as u32;
        if steps > s.max_steps_per_frame {
            self.remaining -= (steps - s.max_steps_per_frame) as f32 * h;
            steps = s.max_steps_per_frame;
        }
        for _ in 0..steps {
            self.substep(h, None);
        }
        self.remaining = (self.remaining - steps as f32 * h).max(0.0);
        Ok(())
    }

    /// One step of `time_step` seconds, the pins where they are now; with `level`, the
    /// free particles keep `radius` out of it (swept from where the step started, sliding;
    /// the contact counts for friction). For callers that drive the steps themselves (the
    /// ropes, which move their pins between steps).
    pub(crate) fn step_once(&mut self, level: Option<&Level>) {
        let h = self.settings.time_step;
        self.substep(h, level);
    }

    /// Sets where pinned particle `i` is held from the next step on (`i` in range).
    pub(crate) fn set_pin_target(&mut self, i: usize, at: Vec3) {
        self.pin_target[i] = Some(at);
    }

    fn substep(&mut self, h: f32, level: Option<&Level>) {
        let s = &self.settings;
        let keep = 1.0 - s.damping;
        let g = s.gravity * (h * h);
        let wind = s.wind * (h * h);
        for i in 0..self.pos.len() {
            let x = self.pos[i];
            if let Some(t) = self.pin_target[i] {
                self.prev[i] = x;
                self.pos[i] = t;
                continue;
            }
            let gust = if s.gust > 0.0 {
                self.rng.range_f32(1.0 - s.gust, 1.0 + s.gust)
            } else {
                1.0
            };
            let next = x + (x - self.prev[i]) * keep + g + wind * gust;
            self.prev[i] = x;
            self.pos[i] = next;
        }
        self.contact.iter_mut().for_each(|c| *c = Vec3::ZERO);
        for _ in 0..s.iterations {
            for st in &self.sticks {
                let (a, b) = (st.a, st.b);
                let d = self.pos[b] - self.pos[a];
                let len = d.length();
                if len < 1e-9 {
                    continue;
                }
                let wa = if self.pin_target[a].is_some() {
                    0.0
                } else {
                    self.inv_mass[a]
                };
                let wb = if self.pin_target[b].is_some() {
                    0.0
                } else {
                    self.inv_mass[b]
                };
                if wa + wb <= 0.0 {
                    continue;
                }
                let corr = d * ((len - st.length) / len * st.stiffness / (wa + wb));
                self.pos[a] += corr * wa;
                self.pos[b] -= corr * wb;
            }
            for ac in &self.angles {
                let c = self.pos[ac.center];
                let (da, db) = (self.pos[ac.a] - c, self.pos[ac.b] - c);
                let angle = da.angle_between(db);
                let (lo, hi) = (ac.min.to_radians(), ac.max.to_radians());
                if !angle.is_finite() || (angle >= lo && angle <= hi) {
                    continue;
                }
                let target = angle.clamp(lo, hi);
                let axis = normalize_or(da.cross(db), da.any_orthonormal_vector());
                // Turn each arm by half the excess, in opposite directions.
                let half = 0.5 * (angle - target);
                if self.pin_target[ac.a].is_none() {
                    self.pos[ac.a] = c + Quat::from_axis_angle(axis, half) * da;
                }
                if self.pin_target[ac.b].is_none() {
                    self.pos[ac.b] = c + Quat::from_axis_angle(axis, -half) * db;
                }
            }
            for i in 0..self.pos.len() {
                if self.pin_target[i].is_some() {
                    continue;
                }
                for col in &self.colliders {
                    let before = self.pos[i];
                    let after = col.resolve(before, self.prev[i], s.radius);
                    if after != before {
                        self.pos[i] = after;
                        self.contact[i] += after - before;
                    }
                }
            }
        }
        // The world has the last word of the step (one BVH query around the particles).
        if let Some(level) = level {
            let (pins, contact, r) = (&self.pin_target, &mut self.contact, self.settings.radius);
            collide_points(
                level,
                &mut self.pos,
                Some(&self.prev),
                0..pins.len(),
                |i| pins[i].is_none(),
                |_| r,
                |i, push| contact[i] += push,
            );
        }
        // Friction once per step: take away part of each touching particle's sliding
        // (tangential) velocity.
        // A contact that pushed the particle out by at least what gravity pushes it in
        // one step gets the whole share; a lighter touch proportionally less, so that a
        // grazing touch does not brake a particle all at once (an on/off friction makes
        // the motion jump with rounding: a rope's swing then parts by centimetres between
        // runs whose inputs differ by a micrometre).
        let friction = self.settings.friction;
        if friction > 0.0 {
            let full = (self.settings.gravity.length() * h * h).max(1e-9);
            for i in 0..self.pos.len() {
                let push = self.contact[i];
                let depth = push.length();
                if depth > 0.0 {
                    let n = push / depth;
                    let share = friction * (depth / full).min(1.0);
                    let v = self.pos[i] - self.prev[i];
                    self.prev[i] += (v - n * v.dot(n)) * share;
                }
            }
        }
        // Never let a non-finite value stay: put such particles back where they were.
        for i in 0..self.pos.len() {
            if !self.pos[i].is_finite() {
                self.pos[i] = self.prev[i];
            }
        }
    }
}
