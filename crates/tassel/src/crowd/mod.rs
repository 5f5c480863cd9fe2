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
#[cfg(target_arch = "x86_64")]
mod avx512;
mod chain;
pub(crate) mod chain_lanes;
mod chain_step;
pub(crate) mod cloth_lanes;
mod entry_lanes;
#[cfg(all(test, target_arch = "x86_64"))]
mod lane_check;
pub mod lanes;
pub(crate) mod spring_lanes;
mod vrm;
pub(crate) mod vrm_contact;

pub use chain::ChainCrowd;
pub use vrm::{CrowdPose, VrmCrowd};

/// Swaps the characters in lanes `i` and `j` of a crowd's lane groups ([`lanes::LANES`]
/// characters each, in index order): `take` copies one lane's state out, `put` writes
/// it into a lane.
fn swap_lanes<P, S>(
    packs: &mut [P],
    i: usize,
    j: usize,
    take: impl Fn(&mut P, usize) -> S,
    put: impl Fn(&mut P, usize, &S),
) {
    use lanes::LANES;
    if i != j {
        let a = take(&mut packs[i / LANES], i % LANES);
        let b = take(&mut packs[j / LANES], j % LANES);
        put(&mut packs[i / LANES], i % LANES, &b);
        put(&mut packs[j / LANES], j % LANES, &a);
    }
}

/// Which code runs a solver step that has a lane path. Every choice gives the same bits
/// (each lane repeats the scalar operations); they differ in speed only.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SimdUse {
    /// The scalar code: the readable reference the lane paths are tested against.
    Scalar,
    /// Lanes in portable code (SSE2 on x86_64), never AVX2.
    Portable,
    /// Lanes with AVX2 where the CPU has it, never AVX-512 (how a CPU without AVX-512
    /// runs `Auto`; to test and measure that code on one with it).
    Avx2,
    /// Lanes with the widest instructions the CPU has (checked at run time): AVX-512
    /// (`avx512f`, `avx512dq`, `avx512vl`, `avx512bw`), else AVX2, else portable.
    #[default]
    Auto,
}

/// The lane code a [`SimdUse`] runs on this CPU ([`Isa::of`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// [`lanes::F`]: plain Rust, vectorised by the compiler for the baseline target.
    Portable,
    /// The AVX2 lane type (`crowd/avx.rs`); only ever made where the CPU has AVX2.
    Avx2,
    /// The AVX-512 lane type (`crowd/avx512.rs`); only ever made where the CPU has it.
    Avx512,
}

impl Isa {
    /// What `simd` runs here ([`SimdUse::Scalar`] has no lane code: portable).
    pub fn of(simd: SimdUse) -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            use std::arch::is_x86_feature_detected as has;
            let avx512 =
                || has!("avx512f") && has!("avx512dq") && has!("avx512vl") && has!("avx512bw");
            match simd {
                SimdUse::Auto if avx512() => Isa::Avx512,
                SimdUse::Auto | SimdUse::Avx2 if has!("avx2") => Isa::Avx2,
                _ => Isa::Portable,
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            let _ = simd;
            Isa::Portable
        }
    }

    /// A name for reports: `portable`, `AVX2` or `AVX-512`.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Portable => "portable",
            Isa::Avx2 => "AVX2",
            Isa::Avx512 => "AVX-512",
        }
    }
}
