//! Which lane code runs: [`SimdUse`] (a user's choice) and [`Isa`] (what it runs on this
//! CPU, decided at run time).

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
    /// [`F`](super::F): plain Rust, vectorised by the compiler for the baseline target.
    Portable,
    /// The AVX2 lane type (`lanes/avx.rs`); only ever made where the CPU has AVX2.
    Avx2,
    /// The AVX-512 lane type (`lanes/avx512.rs`); only ever made where the CPU has it.
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
