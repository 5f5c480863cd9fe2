//! Secondary motion solvers: `chain`, the KawaiiPhysics-style bone chain (seed 000);
//! `spring`, Unreal's spring controller (seed 002); `cloth`, SPCRJointDynamics' bone cloth
//! (seed 004); `particles`, a general Verlet particle-constraint world (seed 001);
//! `rope`, bone chains driven by it; and `vrm`, VRM spring bones by the VRM specification.

pub mod chain;
pub mod cloth;
mod curve;
mod mode;
pub mod particles;
pub(crate) mod path;
mod rig;
pub mod rope;
pub mod spring;
pub mod vrm;
mod world;

pub use curve::Curve;
pub use mode::SimMode;
pub(crate) use rig::CompiledCollider;
pub use rig::{ColliderGroupSettings, ColliderSettings, RigSettings};
