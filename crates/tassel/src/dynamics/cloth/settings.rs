//! Bone-cloth settings (a `[[cloth]]` table of the rig file): plain data.

use crate::dynamics::Curve;
use crate::error::{Error, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Which constraint families a cloth builds (SPCRJointDynamics' switches).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ConstraintSwitches {
    /// Neighbouring points of one chain.
    pub structural_vertical: bool,
    /// Same-index points of neighbouring chains (and last↔first with `loop_chains`).
    pub structural_horizontal: bool,
    /// Both diagonals of every quad between neighbouring chains.
    pub shear: bool,
    /// Points two apart on one chain.
    pub bending_vertical: bool,
    /// Same-index points of chains two apart (wrapping with `loop_chains`).
    pub bending_horizontal: bool,
}

impl Default for ConstraintSwitches {
    fn default() -> Self {
        Self {
            structural_vertical: true,
            structural_horizontal: true,
            shear: true,
            bending_vertical: true,
            bending_horizontal: false,
        }
    }
}

/// One strength curve per constraint family, over the normalised chain position (0 at the
/// roots, 1 at the tips); values 0..=1 are the share of the length error corrected per
/// iteration.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct StrengthCurves {
    /// Structural, along the chains.
    pub structural_vertical: Curve,
    /// Structural, across the chains.
    pub structural_horizontal: Curve,
    /// Shear (quad diagonals).
    pub shear: Curve,
    /// Bending along the chains.
    pub bending_vertical: Curve,
    /// Bending across the chains.
    pub bending_horizontal: Curve,
}

/// Per-point parameter curves over the normalised chain position; each multiplies its
/// base value.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PointCurves {
    /// Multiplies `resistance`.
    pub resistance: Curve,
    /// Multiplies `hardness`.
    pub hardness: Curve,
    /// Multiplies `gravity_scale`.
    pub gravity_scale: Curve,
    /// Multiplies `drag`.
    pub drag: Curve,
    /// Multiplies `lift`.
    pub lift: Curve,
    /// Multiplies `radius`.
    pub radius: Curve,
    /// Multiplies `friction`.
    pub friction: Curve,
}

/// How the cloth's quads meet the colliders.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SurfaceCollision {
    /// Points (and segments, if on) only.
    Off,
    /// A collider closer to a quad than its radius pushes the quad away.
    Push,
    /// Push, and a collider that got through a quad pulls the quad back over it: every
    /// (triangle, collider) pair keeps the side it had when they last met.
    PushPull,
}

/// How a cloth steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClothMode {
    /// Tassel's own step: targets and colliders at each step's time, the output blended
    /// between the last two steps and kept out of this frame's colliders. The same look
    /// at every frame rate. The default.
    #[default]
    Fixed,
    /// SPCRJointDynamicsUE4's update as its code runs it (`AnimNode_SPCRJointDynamics.cpp`):
    /// every step of a frame aims at the frame's pose, colliders swept from the last
    /// frame's place across the iterations, its gravity, resistance, drag, lift, wind and
    /// collision rules, its constraint order, and the bones moved to the points. For a
    /// user bringing an SPCR setup; the look depends on the frame rate as SPCR's does.
    Spcr,
}

/// SPCRJointDynamics' per-family collision switches (`bStructural_Vertical_Collision`…):
/// the families whose constraints push their points, and their segments, out of the
/// colliders in the `spcr` mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionSwitches {
    /// Along the chains (SPCR's default: on).
    pub structural_vertical: bool,
    /// Across the chains (SPCR's default: off).
    pub structural_horizontal: bool,
    /// Quad diagonals (SPCR's default: off).
    pub shear: bool,
}

impl Default for CollisionSwitches {
    fn default() -> Self {
        Self {
            structural_vertical: true,
            structural_horizontal: false,
            shear: false,
        }
    }
}

/// Wind on a cloth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClothWind {
    /// World-space acceleration, m/s².
    pub acceleration: Vec3,
    /// Gust amount 0..=1: each point and step scales the wind by a random factor in
    /// `[1 − gust, 1 + gust]`.
    pub gust: f32,
    /// Seed of the gust generator.
    pub seed: u64,
    /// `spcr` mode only: SPCR's `WindForceSpeed`, radians per second of the wind's cycle
    /// (the wind is `acceleration × (sin(phase)·0.5 + 0.5)`; 0 = no wind, as in SPCR).
    /// Unset: 1, SPCR's default; at most 10 000. The `fixed` mode does not read it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub speed: Option<f32>,
}

impl Default for ClothWind {
    fn default() -> Self {
        Self {
            acceleration: Vec3::ZERO,
            gust: 0.0,
            seed: 1,
            speed: None,
        }
    }
}

/// A mass-spring bone cloth built from parallel bone chains (after SPCRJointDynamics).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ClothSettings {
    /// A name for messages.
    pub name: String,
    /// How it steps: `fixed` (Tassel's, the default) or `spcr` (SPCRJointDynamicsUE4's
    /// update). A rig file's `mode = "spcr"` also gives the keys it leaves out SPCR's
    /// defaults ([`ClothSettings::spcr`]).
    #[serde(skip_serializing_if = "is_fixed")]
    pub mode: ClothMode,
    /// The chains, in order around or across the cloth: `[root bone, end bone]` pairs; each
    /// chain is the end bone and its ancestors up to the root bone.
    pub chains: Vec<[String; 2]>,
    /// Close the ring: the last chain is the first one's neighbour (a skirt).
    pub loop_chains: bool,
    /// Points with index ≤ this on every chain follow the animation (0 = the roots).
    pub fixed_point_index: u32,
    /// Length of an extra tip point past each end bone, metres (0 = none).
    pub virtual_bone_length: f32,
    /// Constraint families built.
    pub constraints: ConstraintSwitches,
    /// Strength against shrinking, per family.
    pub shrink: StrengthCurves,
    /// Strength against stretching, per family.
    pub stretch: StrengthCurves,
    /// Share of the velocity lost per step, 0..=1.
    pub resistance: f32,
    /// Share of the way back to the animated point per step, 0..=1.
    pub hardness: f32,
    /// Gravity, m/s² (world space).
    pub gravity: Vec3,
    /// Multiplies gravity per point.
    pub gravity_scale: f32,
    /// Quadratic air drag, 1/m: speed lost per step is `drag·|v|²·h`.
    pub drag: f32,
    /// Lift, 1/s: acceleration `lift·|v|` across the motion, away from gravity.
    pub lift: f32,
    /// Wind.
    pub wind: ClothWind,
    /// Collision radius of each point, metres.
    pub radius: f32,
    /// Share of a point's velocity lost on the step after it touched a collider, 0..=1.
    pub friction: f32,
    /// Colliders (rig collider names; empty = all).
    pub colliders: Vec<String>,
    /// Also keep the structural segments (not just their points) out of the colliders.
    pub segment_collision: bool,
    /// Collision of the quads.
    pub surface_collision: SurfaceCollision,
    /// Also keep every free point `radius` out of the world: the `Level` given to
    /// `CharacterSim::set_level` (swept from the point's position before the step, sliding,
    /// with the cloth's friction).
    pub world_collision: bool,
    /// Largest angle, degrees, between a segment and where its parent segment's swing
    /// takes its animated direction (0 = no limit).
    pub limit_angle: f32,
    /// Largest speed of a point, m/s (0 = no limit).
    pub max_speed: f32,
    /// After every step, no chain segment is longer than its rest length.
    pub force_length_limit: bool,
    /// Steps per second (SPCRJointDynamics uses 120).
    pub step_rate: f32,
    /// At most this many steps per frame; longer hitches drop time.
    pub max_steps_per_frame: u32,
    /// Constraint iterations per step.
    pub iterations: u32,
    /// Reset when the character moves farther than this in one frame, metres (0 = never).
    pub teleport_distance: f32,
    /// Reset when the character turns more than this in one frame, degrees (0 = never).
    pub teleport_angle: f32,
    /// Per-point parameter curves.
    pub curves: PointCurves,
    /// `spcr` mode only: which families' constraints collide (SPCR's
    /// `b…_Collision`). Unset: [`CollisionSwitches::default`], SPCR's.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision: Option<CollisionSwitches>,
    /// `spcr` mode only: SPCR's `CollisionLOD`, 1..=4: the collision runs on every
    /// `collision_lod`-th step of a frame, counted back from its last step. Unset: 2.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision_lod: Option<u32>,
    /// `spcr` mode only: SPCR's `CollisionSubInterations`, 1..=10: collision passes per
    /// iteration, the colliders swept across them. Unset: 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collision_sub_iterations: Option<u32>,
    /// `spcr` mode only: SPCR's `bLimitFromRoot`: the angle limit measures every segment
    /// from its direction when the cloth was reset, not from its parent segment. Unset:
    /// false.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub limit_from_root: Option<bool>,
    /// `spcr` mode only: SPCR's `Structural_Vertical_StepCount`, 1..=8: how many times the
    /// vertical structural constraints are listed (each relaxed in turn). Unset: 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub structural_vertical_step_count: Option<u32>,
}

fn is_fixed(mode: &ClothMode) -> bool {
    *mode == ClothMode::Fixed
}

impl Default for ClothSettings {
    fn default() -> Self {
        Self {
            name: String::new(),
            mode: ClothMode::Fixed,
            chains: Vec::new(),
            loop_chains: false,
            fixed_point_index: 0,
            virtual_bone_length: 0.0,
            constraints: ConstraintSwitches::default(),
            shrink: StrengthCurves::default(),
            stretch: StrengthCurves::default(),
            resistance: 0.05,
            hardness: 0.0,
            gravity: Vec3::new(0.0, -9.81, 0.0),
            gravity_scale: 1.0,
            drag: 0.0,
            lift: 0.0,
            wind: ClothWind::default(),
            radius: 0.02,
            friction: 0.3,
            colliders: Vec::new(),
            segment_collision: true,
            world_collision: false,
            surface_collision: SurfaceCollision::PushPull,
            limit_angle: 0.0,
            max_speed: 0.0,
            force_length_limit: true,
            step_rate: 120.0,
            max_steps_per_frame: 8,
            iterations: 4,
            teleport_distance: 1.0,
            teleport_angle: 60.0,
            curves: PointCurves::default(),
            collision: None,
            collision_lod: None,
            collision_sub_iterations: None,
            limit_from_root: None,
            structural_vertical_step_count: None,
        }
    }
}

/// The keys whose default differs in the `spcr` mode (SPCRJointDynamicsUE4's defaults),
/// with Tassel's names.
pub(crate) const SPCR_DEFAULTED_KEYS: [&str; 5] = [
    "iterations",
    "force_length_limit",
    "surface_collision",
    "max_steps_per_frame",
    "radius",
];

impl ClothSettings {
    /// A cloth in the `spcr` mode with SPCRJointDynamicsUE4's defaults where they differ
    /// from Tassel's: one iteration (`MaxIterations`), no final length limit
    /// (`bForceLengthLimit`), no surface collision (`bUseSurfaceCollision`), points
    /// without a radius, and no step cap (the hitch guard at its largest, 64 steps).
    pub fn spcr() -> Self {
        let mut s = Self {
            mode: ClothMode::Spcr,
            ..Self::default()
        };
        for key in SPCR_DEFAULTED_KEYS {
            s.set_spcr_default(key);
        }
        s
    }

    /// Sets `key` (one of [`SPCR_DEFAULTED_KEYS`]) to SPCR's default.
    pub(crate) fn set_spcr_default(&mut self, key: &str) {
        match key {
            "iterations" => self.iterations = 1,
            "force_length_limit" => self.force_length_limit = false,
            "surface_collision" => self.surface_collision = SurfaceCollision::Off,
            "max_steps_per_frame" => self.max_steps_per_frame = crate::limits::MAX_STEPS_PER_FRAME,
            "radius" => self.radius = 0.0,
            _ => {}
        }
    }
}

impl ClothSettings {
    /// Checks every parameter; errors name the cloth and the parameter.
    pub fn validate(&self) -> Result<()> {
        let name = &self.name;
        let bad = |what: &str, v: String| {
            Err(Error::InvalidParameter(format!(
                "cloth '{name}': {what} = {v} is out of range"
            )))
        };
        let unit = |what: &str, v: f32| {
            if (0.0..=1.0).contains(&v) {
                Ok(())
            } else {
                bad(what, format!("{v} (0..=1)"))
            }
        };
        let non_neg = |what: &str, v: f32| {
            if v.is_finite() && v >= 0.0 {
                Ok(())
            } else {
                bad(what, format!("{v} (finite, ≥ 0)"))
            }
        };
        if self.chains.len() < 2 {
            return Err(Error::InvalidParameter(format!(
                "cloth '{name}': needs at least two chains, has {}",
                self.chains.len()
            )));
        }
        unit("resistance", self.resistance)?;
        unit("hardness", self.hardness)?;
        unit("friction", self.friction)?;
        unit("wind.gust", self.wind.gust)?;
        non_neg("virtual_bone_length", self.virtual_bone_length)?;
        non_neg("drag", self.drag)?;
        non_neg("lift", self.lift)?;
        non_neg("radius", self.radius)?;
        non_neg("limit_angle", self.limit_angle)?;
        non_neg("max_speed", self.max_speed)?;
        non_neg("teleport_distance", self.teleport_distance)?;
        non_neg("teleport_angle", self.teleport_angle)?;
        if !self.gravity_scale.is_finite() {
            return bad("gravity_scale", format!("{}", self.gravity_scale));
        }
        if !self.gravity.is_finite() {
            return bad("gravity", format!("{}", self.gravity));
        }
        if !self.wind.acceleration.is_finite() {
            return bad("wind.acceleration", format!("{}", self.wind.acceleration));
        }
        if !(self.step_rate.is_finite() && (10.0..=10_000.0).contains(&self.step_rate)) {
            return bad("step_rate", format!("{} (10..=10000)", self.step_rate));
        }
        let max_steps = crate::limits::MAX_STEPS_PER_FRAME;
        if !(1..=max_steps).contains(&self.max_steps_per_frame) {
            return bad(
                "max_steps_per_frame",
                format!("{} (1..={max_steps})", self.max_steps_per_frame),
            );
        }
        if !(1..=64).contains(&self.iterations) {
            return bad("iterations", format!("{} (1..=64)", self.iterations));
        }
        for (family, s, t) in [
            (
                "structural_vertical",
                &self.shrink.structural_vertical,
                &self.stretch.structural_vertical,
            ),
            (
                "structural_horizontal",
                &self.shrink.structural_horizontal,
                &self.stretch.structural_horizontal,
            ),
            ("shear", &self.shrink.shear, &self.stretch.shear),
            (
                "bending_vertical",
                &self.shrink.bending_vertical,
                &self.stretch.bending_vertical,
            ),
            (
                "bending_horizontal",
                &self.shrink.bending_horizontal,
                &self.stretch.bending_horizontal,
            ),
        ] {
            for (kind, c) in [("shrink", s), ("stretch", t)] {
                let what = format!("cloth '{name}': {kind}.{family}");
                c.validate(&what)?;
                if c.keys.iter().any(|k| !(0.0..=1.0).contains(&k[1])) {
                    return Err(Error::InvalidParameter(format!(
                        "{what}: strengths must be within 0..=1"
                    )));
                }
            }
        }
        self.validate_spcr_keys()?;
        let c = &self.curves;
        for (what, curve) in [
            ("resistance", &c.resistance),
            ("hardness", &c.hardness),
            ("gravity_scale", &c.gravity_scale),
            ("drag", &c.drag),
            ("lift", &c.lift),
            ("radius", &c.radius),
            ("friction", &c.friction),
        ] {
            curve.validate(&format!("cloth '{name}': curves.{what}"))?;
        }
        Ok(())
    }

    /// The `spcr` mode's own keys in range.
    fn validate_spcr_keys(&self) -> Result<()> {
        let name = &self.name;
        let range = |what: &str, v: Option<u32>, lo: u32, hi: u32| match v {
            Some(v) if !(lo..=hi).contains(&v) => Err(Error::InvalidParameter(format!(
                "cloth '{name}': {what} = {v} is out of range ({lo}..={hi})"
            ))),
            _ => Ok(()),
        };
        range("collision_lod", self.collision_lod, 1, 4)?;
        range(
            "collision_sub_iterations",
            self.collision_sub_iterations,
            1,
            10,
        )?;
        range(
            "structural_vertical_step_count",
            self.structural_vertical_step_count,
            1,
            8,
        )?;
        if let Some(v) = self.wind.speed {
            if !(v.is_finite() && (0.0..=10_000.0).contains(&v)) {
                return Err(Error::InvalidParameter(format!(
                    "cloth '{name}': wind.speed = {v} is out of range (0..=10000 rad/s)"
                )));
            }
        }
        Ok(())
    }
}
