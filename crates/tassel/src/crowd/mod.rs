//! Crowds: many characters of one kind, sharing one compiled rig, advanced together.
//!
//! A crowd keeps each character's solver state side by side in structure-of-arrays lane
//! groups ([`lanes::LANES`] characters per group, one SIMD lane each) and steps the groups
//! in parallel with rayon (threads of the current rayon pool, deterministic: a character's
//! result never depends on the thread count or on its neighbours). It gives exactly the
//! results of the single-character path ([`crate::CharacterSim`]), which stays the
//! readable reference and against which the crowd is tested bit for bit.
//!
//! - [`VrmCrowd`]: VRM spring bones (`fixed`, `spec` and `three-vrm` modes).
//! - [`ChainCrowd`]: bone chains (both time modes, every collider shape).

#[cfg(target_arch = "x86_64")]
mod avx;
mod chain;
pub(crate) mod chain_lanes;
mod chain_step;
pub(crate) mod cloth_lanes;
mod entry_lanes;
pub mod lanes;
pub(crate) mod spring_lanes;
mod vrm;
pub(crate) mod vrm_contact;

pub use chain::ChainCrowd;
pub use vrm::{CrowdPose, VrmCrowd};

/// Which code runs a solver step that has a lane path. Every choice gives the same bits
/// (each lane repeats the scalar operations); they differ in speed only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SimdUse {
    /// The scalar code: the readable reference the lane paths are tested against.
    Scalar,
    /// Lanes in portable code (SSE2 on x86_64), never AVX2.
    Portable,
    /// Lanes, with AVX2 where the CPU has it (checked at run time).
    #[default]
    Auto,
}
