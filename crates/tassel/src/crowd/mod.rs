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

mod chain;
mod vrm;

pub use crate::lanes::{self, Isa, SimdUse};
pub use crate::pose::CrowdPose;
pub use chain::ChainCrowd;
pub use vrm::VrmCrowd;

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
