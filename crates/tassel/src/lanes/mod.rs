//! SIMD lanes: the layer below the solvers. [`LANES`] `f32`s side by side ([`F`], and
//! [`V3`], [`Q`], [`Trs`] built of them), every operation repeating lane by lane the IEEE
//! operations glam and [`crate::math`] perform for one value, so that code written once
//! over [`Lane`] gives the scalar code's bits in every lane.
//!
//! What a lane holds is the caller's choice: a crowd puts one character in each
//! ([`crate::crowd`]); one character's solvers put twin chains, springs or cloth points
//! side by side (each solver's lane step lives beside its scalar step, e.g.
//! `dynamics/chain/lanes/`). This module knows nothing of solvers or crowds.
//!
//! Back-ends: [`F`] is plain Rust that the compiler vectorises for the baseline target
//! (every target, WebAssembly included); on x86_64 two explicit types, `avx.rs` (two
//! 256-bit registers per value) and `avx512.rs` (one 512-bit register), private to this
//! crate and used only inside functions compiled for their instructions after [`Isa::of`]
//! found the CPU has them; and `narrow.rs`'s four-lane type, one 128-bit register, for
//! one character's springs in WebAssembly.

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512;
#[cfg(all(test, target_arch = "x86_64"))]
pub(crate) mod check;
mod isa;
mod narrow;
mod types;

pub use isa::{Isa, SimdUse};
pub(crate) use narrow::F4;
pub use types::*;
