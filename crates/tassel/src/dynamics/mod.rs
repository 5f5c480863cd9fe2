//! Secondary motion solvers. `chain` is the KawaiiPhysics-style bone chain (seed 000),
//! with colliders, limits, teleport handling and two time modes.

pub mod chain;
mod curve;
pub mod particles;
mod rig;
pub mod spring;

pub use curve::Curve;
pub use rig::{ColliderSettings, RigSettings};
