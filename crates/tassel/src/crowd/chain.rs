//! [`ChainCrowd`]: the bone-chain frame of [`crate::dynamics::chain::ChainJob`] (both time
//! modes) for many characters of one rig, [`LANES`] characters per lane group, the groups
//! spread over the rayon pool's threads. The lane-group frame itself is the chain
//! solver's (`dynamics/chain/lanes/`), which one character's twin chains run too.

use super::{CrowdPose, Frame, LaneStep, Part};
use crate::dynamics::chain::compile::ChainRig;
use crate::dynamics::chain::lanes::{any_planar, Ctx, LaneShape, Pack, Scratch};
use crate::dynamics::path::CharacterPath;
use crate::error::{Error, Result};
use crate::lanes::{Isa, SimdUse, LANES};
use crate::math::Transform;
use crate::pose::LocalToModelJob;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use std::sync::Arc;

/// Many characters with the same bone chains, advanced together.
///
/// Every character shares one skeleton and one compiled [`ChainRig`] (behind [`Arc`]) and
/// has its own state. A frame reads each character's world transform and animated pose
/// through a closure, steps all characters ([`LANES`] per lane group, the groups spread
/// over the current rayon pool's threads) and keeps each character's simulated rotations,
/// which [`ChainCrowd::write_pose`] writes into a pose.
/// Results are those of [`crate::dynamics::chain::ChainJob`] (and so of a
/// [`crate::CharacterSim`] with these chains only) on the same input, bit for bit, in
/// both time modes, and do not depend on the number of threads. The crowd has no level:
/// chains with `world_collision` collide with their colliders only.
///
/// ```
/// use std::sync::Arc;
/// use tassel::crowd::{ChainCrowd, CrowdPose};
/// use tassel::dynamics::chain::ChainRig;
/// use tassel::{builtin, Transform};
///
/// let (skeleton, settings) = builtin::bench_character(4, 5, 2);
/// let rig = Arc::new(ChainRig::new(&skeleton, &settings)?);
/// let skeleton = Arc::new(skeleton);
/// let mut crowd = ChainCrowd::new(skeleton.clone(), rig)?;
/// for _ in 0..20 {
///     crowd.add();
/// }
/// let rest = skeleton.rest().to_vec();
/// for frame in 0..10 {
///     crowd.frame(1.0 / 60.0, |i| CrowdPose {
///         transform: Transform::from_translation(glam::Vec3::X * (i as f32 + frame as f32 * 0.01)),
///         locals: &rest,
///     })?;
/// }
/// let mut locals = rest.clone();
/// let mut models = rest.clone();
/// crowd.write_pose(3, &mut locals, &mut models)?;
/// # Ok::<(), tassel::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct ChainCrowd {
    skeleton: Arc<Skeleton>,
    rig: Arc<ChainRig>,
    packs: Vec<Pack>,
    len: usize,
    scratch: Vec<Scratch>,
    shapes: Vec<LaneShape>,
    simd: SimdUse,
}

impl ChainCrowd {
    /// An empty crowd of characters with `skeleton` and `rig` (compiled for it).
    pub fn new(skeleton: Arc<Skeleton>, rig: Arc<ChainRig>) -> Result<Self> {
        if rig.joint_count() != skeleton.len() {
            return Err(Error::LengthMismatch {
                what: "chain rig joints",
                expected: skeleton.len(),
                got: rig.joint_count(),
            });
        }
        if rig.needs_per_character() {
            return Err(Error::InvalidParameter(
                "a chain crowd cannot step bone constraints, sync bones, external forces, \
                 a simulation space other than the character's, a move scale, a noisy \
                 wind or kawaii mode: run such characters through CharacterSim"
                    .into(),
            ));
        }
        let shapes = rig
            .colliders
            .iter()
            .map(|c| LaneShape::of(c.shape))
            .collect();
        Ok(Self {
            skeleton,
            rig,
            packs: Vec::new(),
            len: 0,
            scratch: Vec::new(),
            shapes,
            simd: SimdUse::Auto,
        })
    }

    /// Adds a character; returns its index. It starts from its pose on its first frame.
    pub fn add(&mut self) -> usize {
        if self.len.is_multiple_of(LANES) {
            self.packs.push(Pack::new(&self.rig));
        }
        let i = self.len;
        let pack = &mut self.packs[i / LANES];
        pack.count += 1;
        pack.clear_lane(&self.rig, i % LANES);
        self.len += 1;
        i
    }

    /// Removes character `i`; the last character takes its index (as `Vec::swap_remove`),
    /// and carries on exactly as it would have.
    pub fn swap_remove(&mut self, i: usize) -> Result<()> {
        self.check(i)?;
        let last = self.len - 1;
        if i != last {
            let moved = self.packs[last / LANES].lane(last % LANES);
            self.packs[i / LANES].set_lane(i % LANES, &moved);
        }
        let pack = &mut self.packs[last / LANES];
        pack.count -= 1;
        if pack.count == 0 {
            self.packs.pop();
        }
        self.len -= 1;
        Ok(())
    }

    /// Swaps characters `i` and `j` (their indices; each carries on exactly as it would
    /// have). Characters share a lane group [`LANES`] at a time, in index order, and a
    /// group costs least when its characters move alike (the same clip near the same
    /// time, the same contacts): the step runs each branch for all of a group's lanes
    /// when any of them needs it: up to 29 % less per joint-step in the bench (`tassel
    /// bench --crowd 192 --phase-step S`; the README's speed section). Allocates (both
    /// characters' state, briefly).
    pub fn swap(&mut self, i: usize, j: usize) -> Result<()> {
        self.check(i)?;
        self.check(j)?;
        super::swap_lanes(&mut self.packs, i, j);
        Ok(())
    }

    /// Which lane code steps the crowd: the widest the CPU has ([`SimdUse::Auto`], the
    /// default: AVX-512, else AVX2, else portable), AVX2 at most ([`SimdUse::Avx2`]) or
    /// the portable code ([`SimdUse::Portable`]; the crowd has no scalar code of its own,
    /// so [`SimdUse::Scalar`] runs that too: its scalar reference is
    /// [`crate::CharacterSim`]). The results are the same bits whichever runs; the
    /// choice is for measuring and testing each.
    pub fn set_simd(&mut self, simd: SimdUse) {
        self.simd = simd;
    }

    /// The characters the last frame held for bad input (index, and what was wrong), in
    /// index order; empty after a good frame.
    pub fn held(&self) -> impl Iterator<Item = (usize, &Error)> + '_ {
        self.packs
            .iter()
            .flat_map(|p| p.held.iter().map(|(i, e)| (*i, e)))
    }

    /// Number of characters.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there is no character.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The shared skeleton.
    pub fn skeleton(&self) -> &Arc<Skeleton> {
        &self.skeleton
    }

    /// The shared rig.
    pub fn rig(&self) -> &Arc<ChainRig> {
        &self.rig
    }

    fn check(&self, i: usize) -> Result<()> {
        if i < self.len {
            Ok(())
        } else {
            Err(Error::InvalidParameter(format!(
                "crowd character {i} does not exist (the crowd has {})",
                self.len
            )))
        }
    }

    /// Makes character `i` start again from its pose on the next frame, wherever it was
    /// before (as a [`crate::CharacterSim`] reset: that frame's time step changes nothing).
    pub fn reset(&mut self, i: usize) -> Result<()> {
        self.check(i)?;
        let pack = &mut self.packs[i / LANES];
        for n in &mut pack.needs_reset {
            n[i % LANES] = true;
        }
        // As `ChainState::reset`: the path before is forgotten.
        pack.paths[i % LANES] = CharacterPath::default();
        Ok(())
    }

    /// Character `i` was moved on purpose: it starts again instead of swinging.
    pub fn teleport(&mut self, i: usize) -> Result<()> {
        self.reset(i)
    }

    /// How many chain resets a teleport (or a non-finite result) caused for character `i`
    /// (as [`crate::dynamics::chain::ChainState::teleport_count`]).
    pub fn teleport_count(&self, i: usize) -> Option<u64> {
        (i < self.len).then(|| self.packs[i / LANES].teleports[i % LANES])
    }

    /// Character `i`'s simulated position of point `point` after the last frame (model
    /// space, as [`crate::dynamics::chain::ChainState::output_positions`]).
    pub fn point(&self, i: usize, point: usize) -> Option<Vec3> {
        if i >= self.len || point >= self.rig.point_count() {
            return None;
        }
        Some(self.packs[i / LANES].out[point].get(i % LANES))
    }

    /// Character `i`'s simulated local rotation of rotator `k` (in
    /// [`ChainRig::rotator_joints`] order) after the last frame: what
    /// [`Self::write_rotations`] writes into that joint.
    pub fn rotation(&self, i: usize, k: usize) -> Option<Quat> {
        if i >= self.len || k >= self.rig.rotators.len() {
            return None;
        }
        Some(self.packs[i / LANES].out_rotation[k].get(i % LANES))
    }

    /// Every character's rotator rotations (as [`Self::rotation`] gives them), character
    /// after character: `out[i * rotators + k]` is character `i`'s rotation `k`, `out`
    /// being [`Self::len`] × the rig's rotators long. One walk over the lane groups.
    /// Never allocates.
    pub fn rotations(&self, out: &mut [Quat]) -> Result<()> {
        let groups = self.packs.iter().map(|p| p.out_rotation.as_slice());
        super::gather_rotations(groups, self.len, self.rig.rotators.len(), out)
    }

    /// Character `i`'s pose after the last frame: `locals` holds its animated pose of that
    /// frame on entry; the chains' rotations are written into it, and `models` receives
    /// the model pose. Never allocates.
    pub fn write_pose(
        &self,
        i: usize,
        locals: &mut [Transform],
        models: &mut [Transform],
    ) -> Result<()> {
        self.write_rotations(i, locals)?;
        LocalToModelJob {
            skeleton: &self.skeleton,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }

    /// Character `i`'s simulated local rotations after the last frame, written into
    /// `locals` (its animated pose of that frame on entry) and nothing else: the local
    /// pose [`Self::write_pose`] gives, without composing the model pose. The chains only
    /// turn joints, so these are every local transform the crowd changes (the joints of
    /// [`ChainRig::rotator_joints`]). Never allocates.
    pub fn write_rotations(&self, i: usize, locals: &mut [Transform]) -> Result<()> {
        self.check(i)?;
        let n = self.skeleton.len();
        if locals.len() != n {
            return Err(Error::LengthMismatch {
                what: "locals",
                expected: n,
                got: locals.len(),
            });
        }
        let pack = &self.packs[i / LANES];
        for (k, (joint, _, _)) in self.rig.rotators.iter().enumerate() {
            locals[*joint as usize].rotation = pack.out_rotation[k].get(i % LANES);
        }
        Ok(())
    }

    /// Advances every character by `dt` seconds (finite, ≥ 0). `input(i)` gives character
    /// `i`'s world transform and animated pose; it is called once per character, from
    /// the rayon pool's threads.
    ///
    /// A character whose input is bad (wrong length, not finite, beyond the limits) is
    /// held: not stepped this frame (its state and results stay as they were, as a
    /// [`crate::CharacterSim`] whose frame fails), while every other character steps as
    /// it would have. The frame then returns the error of the first held character (by
    /// index) and [`Self::held`] lists them all. Never allocates once each thread has
    /// run a frame, except for the characters it holds.
    pub fn frame<'a, I>(&mut self, dt: f32, input: I) -> Result<()>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        if let Some(f) = self.prepare(dt, rayon::current_num_threads().max(1))? {
            f.run_rayon(&input);
        }
        self.result()
    }

    /// [`Self::frame`] with the lane groups cut into `parts` shares that `run` runs on the
    /// caller's threads (a game engine's task pool, instead of rayon's) — each part
    /// exactly once, in any order, in parallel or not — before it returns. The same bits
    /// as [`Self::frame`], whatever the number of parts or threads. `run` gets no part
    /// when the time step is bad (the error is returned) or the crowd is empty.
    pub fn frame_parts<'a, I, R>(&mut self, dt: f32, input: I, parts: usize, run: R) -> Result<()>
    where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
        R: FnOnce(&mut dyn Iterator<Item = ChainCrowdPart<'_, '_, I>>),
    {
        if let Some(mut f) = self.prepare(dt, parts.max(1))? {
            f.run_parts(&input, ChainCrowdPart, run);
        }
        self.result()
    }

    /// A frame's shared part and its lane groups cut into `parts` chunks (each with its
    /// scratch): `None` for an empty crowd.
    fn prepare(&mut self, dt: f32, parts: usize) -> Result<Option<Frame<'_, Ctx<'_>>>> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidTimeStep(dt));
        }
        if self.packs.is_empty() {
            return Ok(None);
        }
        let chunk = self.packs.len().div_ceil(parts);
        let chunks = self.packs.len().div_ceil(chunk);
        while self.scratch.len() < chunks {
            self.scratch
                .push(Scratch::new(&self.rig, self.skeleton.len()));
        }
        Ok(Some(Frame {
            ctx: Ctx {
                sk: &self.skeleton,
                rig: &self.rig,
                shapes: &self.shapes,
                planar: any_planar(&self.rig),
                dt,
                isa: Isa::of(self.simd),
            },
            packs: &mut self.packs,
            scratch: &mut self.scratch[..chunks],
            chunk,
            rest: self.skeleton.rest(),
        }))
    }

    /// The frame's result: the first held character's error.
    fn result(&self) -> Result<()> {
        match self.packs.iter().find_map(|p| p.held.first()) {
            Some((_, e)) => Err(e.clone()),
            None => Ok(()),
        }
    }
}

/// One share of a [`ChainCrowd`] frame's lane groups ([`ChainCrowd::frame_parts`]), to
/// run on any thread.
pub struct ChainCrowdPart<'f, 'c, I>(Part<'f, Ctx<'c>, I>);

impl<'a, I> ChainCrowdPart<'_, '_, I>
where
    I: Fn(usize) -> CrowdPose<'a> + Sync,
{
    /// Steps this share's lane groups.
    pub fn run(self) {
        self.0.run();
    }
}

impl LaneStep for Ctx<'_> {
    type Pack = Pack;
    type Scratch = Scratch;
    fn run_groups<'a, I>(
        &self,
        packs: &mut [Pack],
        scratch: &mut Scratch,
        first: usize,
        input: &I,
        rest: &[Transform],
    ) where
        I: Fn(usize) -> CrowdPose<'a> + Sync,
    {
        for k in 0..packs.len() {
            let (done, later) = packs.split_at_mut(k + 1);
            let (pack, next) = (&mut done[k], later.first());
            // The next group's state, on its way while this group runs (the step and the
            // write-back ask for the rest of it as they go).
            if let Some(next) = next {
                next.prefetch_frame_state();
            }
            let base = (first + k) * LANES;
            let kept = super::run_holding(pack, base, rest, input, |pack, f| {
                self.gather(pack, scratch, base, &f)
            });
            self.step(pack, scratch, true, next);
            super::restore(pack, kept);
        }
    }
}
