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
pub use chain::{ChainCrowd, ChainCrowdPart};
pub use vrm::{VrmCrowd, VrmCrowdPart};

use crate::error::Error;
use crate::math::Transform;
use crate::CharacterRig;
use rayon::prelude::*;

/// The crowd that can step characters of a kind ([`CrowdKind::of`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CrowdKind {
    /// [`VrmCrowd`]: the kind's only solver is VRM spring bones.
    Vrm,
    /// [`ChainCrowd`]: the kind's only solver is bone chains.
    Chains,
}

impl CrowdKind {
    /// Which crowd steps characters of `rig` as [`crate::CharacterSim::from_rig`] would,
    /// bit for bit (a crowd has no level: a `CharacterSim` given one with
    /// [`crate::CharacterSim::set_level`] differs where chains collide with it); `None`
    /// when the kind has springs, cloths or ropes, several kinds of solver, or chains
    /// that need the per-character step ([`crate::dynamics::chain::ChainRig::needs_per_character`]:
    /// [`ChainCrowd`] has no lane step for them).
    pub fn of(rig: &CharacterRig) -> Option<CrowdKind> {
        let others = !rig.springs.is_empty()
            || !rig.cloths.is_empty()
            || !rig.ropes.is_empty()
            || rig.chains.needs_per_character();
        let (vrm, chains) = (!rig.vrm.links.is_empty(), rig.chains.chain_count() > 0);
        match (others, vrm, chains) {
            (false, true, false) => Some(CrowdKind::Vrm),
            (false, false, true) => Some(CrowdKind::Chains),
            _ => None,
        }
    }
}

/// Every character's output rotations into `out`, character after character, slot after
/// slot (`out[i * slots + k]`: character `i`'s rotation `k`), from the lane groups'
/// `out_rotation` lists (`slots` each): what `rotation(i, k)` gives for every `i` and `k`,
/// in one walk over the groups.
fn gather_rotations<'p>(
    groups: impl Iterator<Item = &'p [lanes::Q]>,
    len: usize,
    slots: usize,
    out: &mut [glam::Quat],
) -> crate::error::Result<()> {
    if out.len() != len * slots {
        return Err(Error::LengthMismatch {
            what: "rotations",
            expected: len * slots,
            got: out.len(),
        });
    }
    for (g, rotations) in groups.enumerate() {
        let lanes = (len - g * lanes::LANES).min(lanes::LANES);
        let first = g * lanes::LANES * slots;
        for (k, q) in rotations.iter().enumerate() {
            // The lanes' arrays read in place (`Q::get` copies each array per lane).
            let (x, y, z, w) = (&q.x.0, &q.y.0, &q.z.0, &q.w.0);
            for l in 0..lanes {
                out[first + l * slots + k] = glam::Quat::from_xyzw(x[l], y[l], z[l], w[l]);
            }
        }
    }
    Ok(())
}

/// A lane group as a crowd's frame holds its bad characters: its list of held
/// characters, and one lane's whole state out and back in.
trait Group {
    /// One lane's state.
    type Lane;
    fn held(&mut self) -> &mut Vec<(usize, Error)>;
    fn take(&mut self, l: usize) -> Self::Lane;
    fn put(&mut self, l: usize, s: &Self::Lane);
}

impl Group for crate::dynamics::chain::lanes::Pack {
    type Lane = crate::dynamics::chain::lanes::LaneState;
    fn held(&mut self) -> &mut Vec<(usize, Error)> {
        &mut self.held
    }
    fn take(&mut self, l: usize) -> Self::Lane {
        self.lane(l)
    }
    fn put(&mut self, l: usize, s: &Self::Lane) {
        self.set_lane(l, s)
    }
}

impl Group for crate::dynamics::vrm::lanes::Pack {
    type Lane = crate::dynamics::vrm::lanes::LaneState;
    fn held(&mut self) -> &mut Vec<(usize, Error)> {
        &mut self.held
    }
    fn take(&mut self, l: usize) -> Self::Lane {
        self.lane(l)
    }
    fn put(&mut self, l: usize, s: &Self::Lane) {
        self.set_lane(l, s)
    }
}

/// One character's input as a lane group's frame reads it.
type Input<'p, 'a> = &'p (dyn Fn(usize) -> CrowdPose<'a> + Sync);

/// Runs `attempt` (a lane group's input checks, alone or with its step: `Err((lane, _))`
/// where a lane's input is bad, having touched no state) until it passes, each time with
/// the bad lane's character held: its error recorded, its state kept aside, and a stand-in
/// input for it (the rest pose `rest` at the origin, which every check passes). Lanes are
/// independent, so the others' results are those of a frame without the held characters.
/// Returns the held lanes' states, for [`restore`] after the step.
fn run_holding<'a, 'r, P: Group, I>(
    pack: &mut P,
    base: usize,
    rest: &'r [Transform],
    input: &I,
    mut attempt: impl FnMut(&mut P, Input<'_, 'r>) -> std::result::Result<(), (usize, Error)>,
) -> Vec<(usize, P::Lane)>
where
    I: Fn(usize) -> CrowdPose<'a> + Sync,
    'a: 'r,
{
    pack.held().clear();
    let mut kept = Vec::new();
    let mut held = [false; lanes::LANES];
    loop {
        let h = held;
        let f = |i: usize| -> CrowdPose<'r> {
            if h[i - base] {
                CrowdPose {
                    transform: Transform::IDENTITY,
                    locals: rest,
                }
            } else {
                input(i)
            }
        };
        match attempt(pack, &f) {
            Ok(()) => return kept,
            Err((lane, e)) => {
                held[lane] = true;
                pack.held().push((base + lane, e));
                kept.push((lane, pack.take(lane)));
            }
        }
    }
}

/// The held lanes' states back, as [`run_holding`] kept them.
fn restore<P: Group>(pack: &mut P, kept: Vec<(usize, P::Lane)>) {
    for (l, s) in &kept {
        pack.put(*l, s);
    }
}

/// Swaps the characters in lanes `i` and `j` of a crowd's lane groups ([`lanes::LANES`]
/// characters each, in index order), through [`Group`]'s `take` and `put`.
fn swap_lanes<P: Group>(packs: &mut [P], i: usize, j: usize) {
    use lanes::LANES;
    if i != j {
        let a = packs[i / LANES].take(i % LANES);
        let b = packs[j / LANES].take(j % LANES);
        packs[i / LANES].put(i % LANES, &b);
        packs[j / LANES].put(j % LANES, &a);
    }
}

/// A crowd's lane-group step as its frame runs it, a share of the groups at a time (the
/// VRM and chain contexts).
trait LaneStep: Sync {
    type Pack: Send;
    type Scratch: Send;
    /// Steps lane groups `packs` (the first is group `first`), holding bad characters.
    fn run_groups<'a, I>(
        &self,
        packs: &mut [Self::Pack],
        scratch: &mut Self::Scratch,
        first: usize,
        input: &I,
        rest: &[Transform],
    ) where
        I: Fn(usize) -> CrowdPose<'a> + Sync;
}

/// A frame ready to run: the step's context and the lane groups cut into chunks of
/// `chunk`, each with its scratch.
struct Frame<'f, C: LaneStep> {
    ctx: C,
    packs: &'f mut [C::Pack],
    scratch: &'f mut [C::Scratch],
    chunk: usize,
    rest: &'f [Transform],
}

impl<C: LaneStep> Frame<'_, C> {
    /// Runs every chunk on the current rayon pool's threads.
    fn run_rayon<'a, I>(self, input: &I)
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        let (ctx, chunk, rest) = (&self.ctx, self.chunk, self.rest);
        self.packs
            .par_chunks_mut(chunk)
            .zip(self.scratch.par_iter_mut())
            .enumerate()
            .for_each(|(c, (packs, scratch))| {
                ctx.run_groups(packs, scratch, c * chunk, input, rest)
            });
    }

    /// Gives every chunk to `run` as a [`Part`] (wrapped by `wrap`), to run on the
    /// caller's threads.
    fn run_parts<'s, 'a, I, P, R>(
        &'s mut self,
        input: &'s I,
        wrap: impl Fn(Part<'s, C, I>) -> P,
        run: R,
    ) where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
        R: FnOnce(&mut dyn Iterator<Item = P>),
    {
        let (ctx, chunk, rest) = (&self.ctx, self.chunk, self.rest);
        run(&mut self
            .packs
            .chunks_mut(chunk)
            .zip(self.scratch.iter_mut())
            .enumerate()
            .map(|(c, (packs, scratch))| {
                wrap(Part {
                    ctx,
                    packs,
                    scratch,
                    first: c * chunk,
                    input,
                    rest,
                })
            }));
    }
}

/// One share of a crowd frame's lane groups, to run on any thread (inside the public
/// [`VrmCrowdPart`] and [`ChainCrowdPart`]).
struct Part<'f, C: LaneStep, I> {
    ctx: &'f C,
    packs: &'f mut [C::Pack],
    scratch: &'f mut C::Scratch,
    /// The index of the first lane group.
    first: usize,
    input: &'f I,
    rest: &'f [Transform],
}

impl<'a, C: LaneStep, I> Part<'_, C, I>
where
    I: Fn(usize) -> CrowdPose<'a> + Sync,
{
    fn run(self) {
        self.ctx
            .run_groups(self.packs, self.scratch, self.first, self.input, self.rest);
    }
}
