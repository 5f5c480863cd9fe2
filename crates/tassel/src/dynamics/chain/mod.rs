//! Bone chains after KawaiiPhysics (seed 000): Verlet points on the real bones, damping,
//! stiffness toward the animated pose with the frame-rate exponent, inertia from the
//! character's own motion, gravity, wind, colliders, limits, teleport reset, two time modes
//! and write-back of bone rotations.
//!
//! [`ChainRig`] is compiled once from [`RigSettings`](crate::dynamics::RigSettings) and a
//! skeleton; [`ChainState`] is the small per-character state; [`ChainJob`] runs one frame.

pub(crate) mod compile;
pub(crate) mod constraint;
pub(crate) mod force;
pub(crate) mod job;
pub(crate) mod lanes;
pub(crate) mod overrides;
mod settings;
pub(crate) mod step;
pub(crate) mod sync;
pub(crate) mod wind;

pub use compile::{ChainRig, PointInfo};
pub use constraint::{BoneConstraintOptions, BoneConstraintSettings, Compliance, CompliancePreset};
pub use force::{
    CurveEvaluate, CustomForce, ExternalForceSettings, ForceKind, ForcePoint, ForceSpace, ForceStep,
};
pub use job::{ChainJob, ChainState};
pub use overrides::{envelope_alpha, OverrideHandle, OverrideTiming, SettingsScale, MAX_OVERRIDES};
pub use settings::{
    ChainCurves, ChainSettings, ClassicGravity, PlanarAxis, SimulationSpace, TimeMode, Wind,
};
pub use sync::{SyncBoneSettings, SyncDirection, SyncTargetSettings};
pub use wind::{
    smooth_noise, stable_hash, GustRequest, ProceduralWindSettings, WindSample, MAX_GUSTS,
    MIN_PERIOD,
};
