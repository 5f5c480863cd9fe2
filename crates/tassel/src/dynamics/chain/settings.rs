//! Chain settings: plain, serde-able data, shared between characters.

use crate::dynamics::Curve;
use crate::error::{Error, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// How the solver advances time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeMode {
    /// One step per rendered frame in KawaiiPhysics 1.10's order (seed 000), with the
    /// differences docs/rig.md lists; the look depends on the frame rate.
    Classic,
    /// Steps of `1 / target_framerate` seconds with the animated targets interpolated across
    /// the sub-steps and the output interpolated between the last two steps: the look no
    /// longer depends on the frame rate.
    #[default]
    Fixed,
    /// KawaiiPhysics 1.21's fixed substepping (its default, `bUseFixedSubstepping`), as
    /// its code runs: steps of `1 / target_framerate` (f32), an accumulator capped at
    /// `max_substeps` steps (the excess dropped), pose targets interpolated across the
    /// substeps, the character's motion shared out by step and carried over by the part
    /// of the frame consumed, 1.20's phase order, no output interpolation.
    Kawaii,
}

/// How `classic` mode applies gravity each frame (KawaiiPhysics changed it twice).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClassicGravity {
    /// `x += g·dt`, as seed 000 writes it (KawaiiPhysics before 1.3.1; later kept behind a
    /// console variable). Gravity then acts as an acceleration of `g / dt`.
    #[default]
    PerFrame,
    /// `x += ½·g·dt²`: KawaiiPhysics' default from 1.3.1 to 1.19 (1.10 included).
    HalfDtSquared,
    /// `x += g·dt²`: KawaiiPhysics' default from 1.20.
    DtSquared,
}

/// Restricts a bone to a plane through its parent, normal to one of the parent's animated
/// axes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanarAxis {
    /// No planar constraint.
    #[default]
    None,
    /// Plane normal is the parent's local X axis.
    X,
    /// Plane normal is the parent's local Y axis.
    Y,
    /// Plane normal is the parent's local Z axis.
    Z,
}

impl PlanarAxis {
    /// The plane's normal in the parent's local space (`None`: no constraint).
    pub(crate) fn axis(self) -> Option<glam::Vec3> {
        match self {
            PlanarAxis::None => None,
            PlanarAxis::X => Some(glam::Vec3::X),
            PlanarAxis::Y => Some(glam::Vec3::Y),
            PlanarAxis::Z => Some(glam::Vec3::Z),
        }
    }
}

/// The space a chain simulates in (KawaiiPhysics 1.19's `SimulationSpace`): what the
/// points keep still while nothing pulls them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SimulationSpace {
    /// The character's space: its motion reaches the points as inertia, scaled by
    /// `world_damping_location` / `_rotation` and `skel_comp_move_scale`.
    #[default]
    #[serde(alias = "component_space")]
    Component,
    /// World space: the points keep their place in the world while the character moves
    /// (full inertia; the world damping keys are not read).
    #[serde(alias = "world_space")]
    World,
    /// A bone's space (`simulation_base_bone`, an ancestor of the chain's root): the
    /// points ride with that bone's animated motion (a dancing pelvis does not whip the
    /// skirt); the character's motion reaches them as in `component`.
    #[serde(alias = "base_bone_space")]
    BaseBone,
}

/// Wind: a push along a world direction with seeded random gusts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wind {
    /// World-space direction (normalised on use; zero means no wind).
    pub direction: Vec3,
    /// Strength: displacement per target frame in metres before damping (≥ 0).
    pub speed: f32,
    /// Gust amount 0..=1: each point and step scales the wind by a random factor in
    /// `[1 − gust, 1 + gust]` (KawaiiPhysics uses 1, i.e. `[0, 2]`).
    pub gust: f32,
    /// Seed of the gust generator.
    pub seed: u64,
    /// Each point and step turns the wind by a random angle up to this, degrees, 0..=180
    /// (KawaiiPhysics' `WindDirectionNoiseAngle`; 0: none).
    #[serde(skip_serializing_if = "is_zero")]
    pub direction_noise_angle: f32,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

fn is_four(n: &u32) -> bool {
    *n == 4
}

fn is_one(v: &Vec3) -> bool {
    *v == Vec3::ONE
}

fn is_component(v: &SimulationSpace) -> bool {
    *v == SimulationSpace::Component
}

impl Default for Wind {
    fn default() -> Self {
        Self {
            direction: Vec3::X,
            speed: 0.0,
            gust: 1.0,
            seed: 1,
            direction_noise_angle: 0.0,
        }
    }
}

/// Parameter curves over the normalised chain length; each multiplies its base value.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChainCurves {
    /// Multiplies `damping`.
    pub damping: Curve,
    /// Multiplies `stiffness`.
    pub stiffness: Curve,
    /// Multiplies `radius`.
    pub radius: Curve,
    /// Multiplies `world_damping_location`.
    pub world_damping_location: Curve,
    /// Multiplies `world_damping_rotation`.
    pub world_damping_rotation: Curve,
    /// Multiplies `limit_angle`.
    pub limit_angle: Curve,
}

/// One bone chain: a root bone and all its descendants (minus excluded subtrees).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ChainSettings {
    /// A name for messages and output.
    pub name: String,
    /// The root bone: it stays animated and turns toward its simulated children.
    pub root: String,
    /// Bones whose subtrees are left out of the chain.
    pub exclude: Vec<String>,
    /// Velocity damping per step, 0..=1.
    pub damping: f32,
    /// Pull toward the animated pose, 0..=1 (1: the animated pose exactly).
    pub stiffness: f32,
    /// How much of the character's own translation the points ignore, 0..=1 (0: full
    /// inertia, they stay where they were in the world; 1: they move with the character).
    pub world_damping_location: f32,
    /// The same for the character's rotation, 0..=1.
    pub world_damping_rotation: f32,
    /// Collision radius of each point, metres (≥ 0).
    pub radius: f32,
    /// Cone limit around the animated bone direction, degrees (0 = off, up to 180).
    pub limit_angle: f32,
    /// Parameter curves over the normalised length.
    pub curves: ChainCurves,
    /// Length of a virtual tip bone added after each leaf, metres (0 = none).
    pub dummy_bone_length: f32,
    /// Planar constraint axis.
    pub planar_constraint: PlanarAxis,
    /// Gravity. In `fixed` mode an acceleration (m/s²); in `classic` mode applied as
    /// `classic_gravity` says (by default as seed 000 writes it, `location += gravity · dt`
    /// each frame).
    pub gravity: Vec3,
    /// `classic` mode: which KawaiiPhysics gravity step to use.
    pub classic_gravity: ClassicGravity,
    /// Gravity given in world space (true) or the character's space (false).
    pub gravity_in_world: bool,
    /// Wind.
    pub wind: Wind,
    /// The frame rate the parameters were tuned for (Hz, > 0); also the `fixed` step rate.
    pub target_framerate: f32,
    /// Time mode.
    pub mode: TimeMode,
    /// Character moves farther than this in one frame: reset to the animated pose
    /// (metres; 0 = off).
    pub teleport_distance: f32,
    /// Character turns more than this in one frame: reset (degrees; 0 = off).
    pub teleport_rotation: f32,
    /// Steps run on the first frame and after each reset to settle the chain.
    pub warmup_steps: u32,
    /// Blend of the result with the animated pose, 0..=1 (1: fully simulated).
    pub alpha: f32,
    /// Colliders (by name from the rig) this chain collides with; empty: all of them.
    pub colliders: Vec<String>,
    /// Also keep every point `radius` out of the world (the [`crate::controller::Level`]
    /// handed to the frame), swept and sliding.
    pub world_collision: bool,
    /// Also collide with the colliders other characters share with this one
    /// ([`crate::CharacterSim::set_shared_colliders`]: a cape against another character's
    /// body, hair against a held prop; KawaiiPhysics' `bUseSharedCollision`).
    #[serde(skip_serializing_if = "is_false")]
    pub use_shared_collision: bool,
    /// `fixed` mode: at most this many steps per frame; time beyond is dropped (hitch guard).
    pub max_steps_per_frame: u32,
    /// `classic` mode: a longer frame is clamped to this, seconds.
    pub max_delta_time: f32,
    /// `kawaii` mode: at most this many substeps per frame (KawaiiPhysics' `MaxSubsteps`,
    /// 1..=16, default 4); the time beyond is dropped.
    #[serde(skip_serializing_if = "is_four")]
    pub max_substeps: u32,
    /// The space the chain simulates in.
    #[serde(skip_serializing_if = "is_component")]
    pub simulation_space: SimulationSpace,
    /// `simulation_space = "base_bone"`: the bone whose space it is (an ancestor of `root`).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub simulation_base_bone: String,
    /// Per character axis, the share of the character's translation that reaches the
    /// points as inertia (KawaiiPhysics' `SkelCompMoveScale`; 0..=10 each, `[1, 1, 1]`:
    /// all; `[1, 0, 1]`: a jump does not lift the hair).
    #[serde(skip_serializing_if = "is_one")]
    pub skel_comp_move_scale: Vec3,
    /// Points put between each bone and its child, and between a leaf and its virtual tip
    /// (KawaiiPhysics 1.21's `BoneSubdivisionCount`, 0..=10; 0: none): evenly spaced on
    /// the segment, so that colliders meet the bone along its length, not only at its
    /// ends. Chains with them step per character (not in lanes).
    #[serde(skip_serializing_if = "is_zero_u32")]
    pub bone_subdivision_count: u32,
    /// The points between bones only collide (KawaiiPhysics' `bBoneSubdivisionCollisionOnly`,
    /// default true): they are placed on the segment between the simulated bone and its
    /// simulated child each step, pushed by the colliders, and the child hangs from them;
    /// a chain that touches nothing moves as without them. False: they are simulated as
    /// bones of their own (inertia, stiffness, gravity).
    #[serde(skip_serializing_if = "is_true")]
    pub bone_subdivision_collision_only: bool,
    /// Put more points where a segment is longer than the points' diameter, so that their
    /// spheres touch along it (KawaiiPhysics' `bBoneSubdivisionDensifyByRadius`: at least
    /// `ceil(length / (2 · radius)) − 1` on a segment, the radius the smallest the radius
    /// curve gives over the chain, at most 50 a segment).
    #[serde(skip_serializing_if = "is_false")]
    pub bone_subdivision_densify_by_radius: bool,
}

fn is_zero_u32(n: &u32) -> bool {
    *n == 0
}

fn is_true(b: &bool) -> bool {
    *b
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl Default for ChainSettings {
    fn default() -> Self {
        Self {
            name: String::new(),
            root: String::new(),
            exclude: Vec::new(),
            damping: 0.1,
            stiffness: 0.05,
            world_damping_location: 0.8,
            world_damping_rotation: 0.8,
            radius: 0.02,
            limit_angle: 0.0,
            curves: ChainCurves::default(),
            dummy_bone_length: 0.0,
            planar_constraint: PlanarAxis::None,
            gravity: Vec3::new(0.0, -9.81, 0.0),
            gravity_in_world: true,
            classic_gravity: ClassicGravity::PerFrame,
            wind: Wind::default(),
            target_framerate: 60.0,
            mode: TimeMode::Fixed,
            teleport_distance: 1.0,
            teleport_rotation: 60.0,
            warmup_steps: 0,
            alpha: 1.0,
            colliders: Vec::new(),
            world_collision: false,
            use_shared_collision: false,
            max_steps_per_frame: 10,
            max_delta_time: 0.1,
            max_substeps: 4,
            simulation_space: SimulationSpace::Component,
            simulation_base_bone: String::new(),
            skel_comp_move_scale: Vec3::ONE,
            bone_subdivision_count: 0,
            bone_subdivision_collision_only: true,
            bone_subdivision_densify_by_radius: false,
        }
    }
}

impl ChainSettings {
    /// Checks every parameter's range; the error names the chain and the parameter.
    pub fn validate(&self) -> Result<()> {
        let name = &self.name;
        let bad = |m: String| Err(Error::InvalidParameter(format!("chain '{name}': {m}")));
        for (param, v) in [
            ("damping", self.damping),
            ("stiffness", self.stiffness),
            ("world_damping_location", self.world_damping_location),
            ("world_damping_rotation", self.world_damping_rotation),
            ("alpha", self.alpha),
            ("wind.gust", self.wind.gust),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(format!("{param} is {v}; it must be between 0 and 1"));
            }
        }
        for (param, v) in [
            ("radius", self.radius),
            ("dummy_bone_length", self.dummy_bone_length),
            ("teleport_distance", self.teleport_distance),
            ("teleport_rotation", self.teleport_rotation),
            ("wind.speed", self.wind.speed),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{param} is {v}; it must be finite and ≥ 0"));
            }
        }
        if !(0.0..=180.0).contains(&self.limit_angle) {
            return bad(format!(
                "limit_angle is {}; it must be 0..=180 degrees",
                self.limit_angle
            ));
        }
        if !(self.target_framerate.is_finite()
            && self.target_framerate >= 1.0
            && self.target_framerate <= 10_000.0)
        {
            return bad(format!(
                "target_framerate is {}; it must be 1..=10000 Hz",
                self.target_framerate
            ));
        }
        if !(self.max_delta_time.is_finite() && self.max_delta_time > 0.0) {
            return bad(format!(
                "max_delta_time is {}; it must be > 0",
                self.max_delta_time
            ));
        }
        let max_steps = crate::limits::MAX_STEPS_PER_FRAME;
        if !(1..=max_steps).contains(&self.max_steps_per_frame) {
            return bad(format!(
                "max_steps_per_frame is {}; it must be 1..={max_steps}",
                self.max_steps_per_frame
            ));
        }
        if self.bone_subdivision_count > 10 {
            return bad(format!(
                "bone_subdivision_count is {}; it must be 0..=10",
                self.bone_subdivision_count
            ));
        }
        if !(1..=16).contains(&self.max_substeps) {
            return bad(format!(
                "max_substeps is {}; it must be 1..=16",
                self.max_substeps
            ));
        }
        let max_warmup = crate::limits::MAX_WARMUP_STEPS;
        if self.warmup_steps > max_warmup {
            return bad(format!(
                "warmup_steps is {}; it must be 0..={max_warmup}",
                self.warmup_steps
            ));
        }
        if !self.gravity.is_finite() {
            return bad(format!("gravity {} is not finite", self.gravity));
        }
        if !(0.0..=180.0).contains(&self.wind.direction_noise_angle) {
            return bad(format!(
                "wind.direction_noise_angle is {}; it must be 0..=180 degrees",
                self.wind.direction_noise_angle
            ));
        }
        let m = self.skel_comp_move_scale;
        if !(m.is_finite() && m.min_element() >= 0.0 && m.max_element() <= 10.0) {
            return bad(format!(
                "skel_comp_move_scale {m} must be 0..=10 on each axis"
            ));
        }
        match (self.simulation_space, self.simulation_base_bone.is_empty()) {
            (SimulationSpace::BaseBone, true) => {
                return bad("simulation_space = \"base_bone\" needs simulation_base_bone".into())
            }
            (SimulationSpace::Component | SimulationSpace::World, false) => {
                return bad(format!(
                    "simulation_base_bone '{}' is set but simulation_space is not \"base_bone\"",
                    self.simulation_base_bone
                ))
            }
            _ => {}
        }
        if !self.wind.direction.is_finite() {
            return bad(format!(
                "wind.direction {} is not finite",
                self.wind.direction
            ));
        }
        let c = &self.curves;
        for (param, curve) in [
            ("curves.damping", &c.damping),
            ("curves.stiffness", &c.stiffness),
            ("curves.radius", &c.radius),
            ("curves.world_damping_location", &c.world_damping_location),
            ("curves.world_damping_rotation", &c.world_damping_rotation),
            ("curves.limit_angle", &c.limit_angle),
        ] {
            curve.validate(&format!("chain '{name}': {param}"))?;
        }
        Ok(())
    }
}
