//! [`VrmCrowd`]: the VRM spring-bone frame of [`crate::dynamics::vrm::VrmJob`] (every
//! mode) for many characters of one rig, [`LANES`] characters per lane group, the groups
//! spread over the rayon pool's threads. The lane-group frame itself is the VRM solver's
//! (`dynamics/vrm/lanes/`).

use super::{CrowdPose, Frame, LaneStep, Part};
use crate::dynamics::path::CharacterPath;
use crate::dynamics::vrm::lanes::{Ctx, Pack, Plan, Scratch};
use crate::dynamics::vrm::{VrmMode, VrmRig};
use crate::error::{Error, Result};
use crate::lanes::{Isa, SimdUse, LANES};
use crate::math::Transform;
use crate::pose::LocalToModelJob;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use std::sync::Arc;

/// Many characters with the same VRM spring bones, advanced together.
///
/// Every character shares one skeleton and one compiled [`VrmRig`] (behind [`Arc`]) and
/// has its own state: a character costs its state only (about 60 bytes per spring joint).
/// A frame reads each character's world transform and animated pose through a closure,
/// steps all characters ([`LANES`] per lane group, the groups spread over the current
/// rayon pool's threads) and keeps each character's simulated rotations, which
/// [`VrmCrowd::write_pose`] writes into a pose.
///
/// Results are those of [`crate::CharacterSim::with_vrm`] on the same input, bit for
/// bit, and do not depend on the number of threads. Every mode: `fixed` (steps at the rig's
/// rate with the pose and the character transform interpolated, output between the last
/// two steps), `spec` and `three-vrm`.
///
/// ```
/// use std::sync::Arc;
/// use tassel::crowd::{CrowdPose, VrmCrowd};
/// use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig};
/// use tassel::{builtin, Transform};
///
/// let (skeleton, bones) = builtin::bench_vrm(4, 5, 2);
/// let options = VrmOptions { mode: VrmMode::Spec, ..Default::default() };
/// let rig = Arc::new(VrmRig::new(&skeleton, &bones, options)?);
/// let skeleton = Arc::new(skeleton);
/// let mut crowd = VrmCrowd::new(skeleton.clone(), rig)?;
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
pub struct VrmCrowd {
    skeleton: Arc<Skeleton>,
    rig: Arc<VrmRig>,
    plan: Plan,
    /// Every joint, ascending ([`Self::input_joints`] with node constraints).
    all_joints: Vec<usize>,
    packs: Vec<Pack>,
    len: usize,
    scratch: Vec<Scratch>,
    /// Per frame: each link's `stiffness · dt` and `gravity · dt`.
    stiffness_dt: Vec<f32>,
    external: Vec<Vec3>,
    simd: SimdUse,
}

impl VrmCrowd {
    /// An empty crowd of characters with `skeleton` and `rig` (compiled for it).
    pub fn new(skeleton: Arc<Skeleton>, rig: Arc<VrmRig>) -> Result<Self> {
        if rig.joint_count() != skeleton.len() {
            return Err(Error::LengthMismatch {
                what: "VRM rig joints",
                expected: skeleton.len(),
                got: rig.joint_count(),
            });
        }
        let plan = Plan::new(&skeleton, &rig)?;
        let links = rig.links.len();
        let all_joints = (0..skeleton.len()).collect();
        Ok(Self {
            skeleton,
            rig,
            plan,
            all_joints,
            packs: Vec::new(),
            len: 0,
            scratch: Vec::new(),
            stiffness_dt: vec![0.0; links],
            external: vec![Vec3::ZERO; links],
            simd: SimdUse::Auto,
        })
    }

    /// Adds a character; returns its index. It starts from its pose on its first frame.
    pub fn add(&mut self) -> usize {
        if self.len.is_multiple_of(LANES) {
            self.packs
                .push(Pack::new(self.rig.links.len(), self.plan.joints.len()));
        }
        let i = self.len;
        let pack = &mut self.packs[i / LANES];
        pack.count += 1;
        // A lane a removed character left: start it afresh.
        let lane = i % LANES;
        pack.needs_reset[lane] = true;
        pack.resets[lane] = 0;
        pack.accumulator[lane] = 0.0;
        pack.paths[lane] = CharacterPath::default();
        // Its input is new: the group's kept pose is not it.
        pack.unchanged[lane] = false;
        pack.prev_is_input = false;
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
        pack.needs_reset[last % LANES] = true;
        pack.unchanged[last % LANES] = false;
        if pack.count == 0 {
            self.packs.pop();
        }
        self.len -= 1;
        Ok(())
    }

    /// Swaps characters `i` and `j` (their indices; each carries on exactly as it would
    /// have). Characters share a lane group [`LANES`] at a time, in index order; which
    /// ones share a group changes the VRM crowd's cost little (about 3 % between
    /// characters that move alike and characters that do not, `tassel bench --vrm spec
    /// --crowd 192 --phase-step S`), the chain crowd's much more
    /// ([`super::ChainCrowd::swap`]). Allocates (both characters' state, briefly).
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
    pub fn rig(&self) -> &Arc<VrmRig> {
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
        pack.needs_reset[i % LANES] = true;
        // As `VrmState::reset`: the path before is forgotten.
        pack.paths[i % LANES] = CharacterPath::default();
        Ok(())
    }

    /// Promises that character `i`'s animated locals in the next frame's input are, bit
    /// for bit, those of the last frame that ran (its world transform may change): a
    /// character no clip moves, only carried. For the next frame only. In `fixed` mode
    /// (the default), a lane group whose characters are all marked, and whose last frame
    /// kept its input as it came (no character reset, held or moved into it), reuses
    /// that kept pose instead of reading and checking every character's input again:
    /// the same bits as without the mark, at less cost (the Bevy plugin marks the members
    /// whose bones did not change). Elsewhere the mark changes nothing. A wrong mark
    /// steps the group on last frame's pose, as if the caller had given it; the input's
    /// length and transform are checked all the same. Mark after [`Self::swap`] and
    /// [`Self::swap_remove`], which forget the marks of the characters they move.
    pub fn mark_pose_unchanged(&mut self, i: usize) -> Result<()> {
        self.check(i)?;
        self.packs[i / LANES].unchanged[i % LANES] = true;
        Ok(())
    }

    /// Character `i` was moved on purpose: it starts again instead of whipping.
    pub fn teleport(&mut self, i: usize) -> Result<()> {
        self.reset(i)
    }

    /// How many resets character `i` had (first frame, teleports, non-finite recoveries).
    pub fn reset_count(&self, i: usize) -> Option<u64> {
        (i < self.len).then(|| self.packs[i / LANES].resets[i % LANES])
    }

    /// Character `i`'s local rotation of link `link` (in [`VrmRig::links`] order).
    pub fn rotation(&self, i: usize, link: usize) -> Option<Quat> {
        if i >= self.len || link >= self.rig.links.len() {
            return None;
        }
        Some(self.packs[i / LANES].out_rotation[link].get(i % LANES))
    }

    /// Every character's link rotations (as [`Self::rotation`] gives them), character after
    /// character: `out[i * links + k]` is character `i`'s rotation of link `k`, `out` being
    /// [`Self::len`] × the rig's links long. One walk over the lane groups: the way to read
    /// them all. Never allocates.
    pub fn rotations(&self, out: &mut [Quat]) -> Result<()> {
        let groups = self.packs.iter().map(|p| p.out_rotation.as_slice());
        super::gather_rotations(groups, self.len, self.rig.links.len(), out)
    }

    /// Character `i`'s current tail of link `link`, world space (or its spring's centre
    /// space when the spring has a centre), as the last frame left it.
    pub fn tail(&self, i: usize, link: usize) -> Option<Vec3> {
        if i >= self.len || link >= self.rig.links.len() {
            return None;
        }
        Some(self.packs[i / LANES].current_tail[link].get(i % LANES))
    }

    /// Character `i`'s pose after the last frame: `locals` holds its animated pose of that
    /// frame on entry; the node constraints and the springs' rotations are written into
    /// it, and `models` receives the model pose. Never allocates.
    pub fn write_pose(
        &self,
        i: usize,
        locals: &mut [Transform],
        models: &mut [Transform],
    ) -> Result<()> {
        self.check(i)?;
        let sk = &*self.skeleton;
        LocalToModelJob {
            skeleton: sk,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()?;
        if !self.rig.constraints.list.is_empty() {
            let component = self.packs[i / LANES].prev_component.get(i % LANES);
            self.rig.constraints.apply(sk, &component, locals, models);
        }
        let pack = &self.packs[i / LANES];
        for (k, l) in self.rig.links.iter().enumerate() {
            locals[l.joint].rotation = pack.out_rotation[k].get(i % LANES);
        }
        LocalToModelJob {
            skeleton: sk,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }

    /// Character `i`'s spring rotations after the last frame, written into `locals` (its
    /// animated pose of that frame on entry) and nothing else, without composing a model
    /// pose. Without node constraints these are every local transform the crowd changes,
    /// and `locals` ends as [`Self::write_pose`] leaves it; with node constraints (the rig's
    /// `constraints`) the constrained joints turn too, which only `write_pose` gives.
    /// Never allocates.
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
        for (k, l) in self.rig.links.iter().enumerate() {
            locals[l.joint].rotation = pack.out_rotation[k].get(i % LANES);
        }
        Ok(())
    }

    /// The joints whose animated local transforms a frame uses (every link, tail, centre
    /// and collider joint and their ancestors; every joint when the rig has node
    /// constraints), ascending. The other joints' input is only checked against the
    /// limits: a caller may leave them at rest.
    pub fn input_joints(&self) -> &[usize] {
        if self.rig.constraints.list.is_empty() {
            &self.plan.joints
        } else {
            &self.all_joints
        }
    }

    /// Advances every character by `dt` seconds (finite, ≥ 0; the first frame of a
    /// character only takes its pose, whatever `dt`). `input(i)` gives character `i`'s
    /// world transform and animated pose; it is called from the rayon pool's threads, at
    /// least once per character and sometimes more (a lane group's input is asked for
    /// ahead of its step, to prefetch it; a group with a bad input is gathered again), so
    /// keep it cheap and free of side effects.
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
        R: FnOnce(&mut dyn Iterator<Item = VrmCrowdPart<'_, '_, I>>),
    {
        if let Some(mut f) = self.prepare(dt, parts.max(1))? {
            f.run_parts(&input, VrmCrowdPart, run);
        }
        self.result()
    }

    /// A frame's shared part and its lane groups cut into `parts` chunks (each with its
    /// scratch): `None` for an empty crowd.
    fn prepare(&mut self, dt: f32, parts: usize) -> Result<Option<Frame<'_, Ctx<'_>>>> {
        if !(dt.is_finite() && dt >= 0.0) {
            // No frame ran: the marks were for this one.
            for pack in &mut self.packs {
                pack.unchanged = [false; LANES];
            }
            return Err(Error::InvalidTimeStep(dt));
        }
        if self.packs.is_empty() {
            return Ok(None);
        }
        // The update's time step: the frame's, or fixed mode's step.
        let h = match self.rig.options.mode {
            VrmMode::Fixed => 1.0 / self.rig.options.step_rate,
            _ => dt,
        };
        for (k, l) in self.rig.links.iter().enumerate() {
            self.stiffness_dt[k] = l.stiffness * h;
            self.external[k] = l.gravity * h;
        }
        let chunk = self.packs.len().div_ceil(parts);
        let chunks = self.packs.len().div_ceil(chunk);
        while self.scratch.len() < chunks {
            self.scratch
                .push(Scratch::new(&self.plan, self.skeleton.len()));
        }
        Ok(Some(Frame {
            ctx: Ctx {
                sk: &self.skeleton,
                rig: &self.rig,
                plan: &self.plan,
                stiffness_dt: &self.stiffness_dt,
                external: &self.external,
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

/// One share of a [`VrmCrowd`] frame's lane groups ([`VrmCrowd::frame_parts`]), to run on
/// any thread.
pub struct VrmCrowdPart<'f, 'c, I>(Part<'f, Ctx<'c>, I>);

impl<'a, I> VrmCrowdPart<'_, '_, I>
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
        let n = packs.len();
        for k in 0..n {
            if k + 1 < n {
                // The next group's input on its way while this one steps: its gather
                // reads sixteen characters' buffers side by side, which the processor's
                // own prefetch does not follow (under `tassel bench --cold`, six
                // alternating pairs: 0.79-0.98 of the frame without it).
                self.prefetch_input(&packs[k + 1], (first + k + 1) * LANES, input);
            }
            let pack = &mut packs[k];
            let base = (first + k) * LANES;
            let kept = super::run_holding(pack, base, rest, input, |pack, f| {
                self.run(pack, scratch, base, &f)
            });
            super::restore(pack, kept);
        }
    }
}
