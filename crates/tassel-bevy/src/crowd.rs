//! Characters of one kind stepped together: a [`VrmCrowd`] or a [`ChainCrowd`] per compiled
//! rig ([`CrowdKind::of`]), with the characters' animated input and the simulated output in
//! flat buffers, one slot per character.

use crate::convert::{to_bevy, to_tassel, world_of};
use crate::crowd_bones::{Access, CrowdBone, ReadView, WriteView, WrittenBone, NOT_WRITTEN};
use bevy::ecs::prelude::*;
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{ChildOf, Quat, Transform as BevyTransform};
use bevy::tasks::ComputeTaskPool;
use std::sync::Arc;
use tassel::crowd::{ChainCrowd, CrowdKind, CrowdPose, VrmCrowd};
use tassel::{CharacterRig, Error, Transform};

/// The crowd of one kind (one per kind, so their sizes do not matter).
#[allow(clippy::large_enum_variant)]
pub(crate) enum Run {
    Vrm(VrmCrowd),
    Chains(ChainCrowd),
}

/// One kind of character stepped as a crowd, and its members' buffers.
pub(crate) struct Kind {
    pub(crate) rig: Arc<CharacterRig>,
    pub(crate) run: Run,
    /// Crowd index → the character entity.
    pub(crate) members: Vec<Entity>,
    /// Each member's animated local pose (every joint, the skeleton's order), member
    /// after member: the joints not in `read` stay at rest.
    pub(crate) locals: Vec<Transform>,
    /// Each member's world transform (of the skeleton's model space).
    pub(crate) roots: Vec<Transform>,
    /// The joints whose animated locals the crowd uses (read from the bones each frame).
    pub(crate) read: Vec<usize>,
    /// The crowd changes only rotations of joints it lists, so the write-back copies those;
    /// with VRM node constraints, the whole pose is composed (`write_pose`) instead.
    pub(crate) whole_pose: bool,
    /// Each write part's scratch pose (locals, models).
    pub(crate) scratch: Vec<(Vec<Transform>, Vec<Transform>)>,
    /// The joints written back (the kind's simulated joints, ascending; each has a bone
    /// entity, or the character would not have started).
    pub(crate) written: Vec<usize>,
    /// For each slot of `read`: its index in `written`, when the plugin writes that joint.
    pub(crate) read_written: Vec<Option<usize>>,
    /// Member after member: the bone entity of each `read` joint (`None`: not found,
    /// the joint stays at rest).
    pub(crate) read_bones: Vec<Option<Entity>>,
    /// Member after member: the bone entity of each `written` joint.
    pub(crate) write_bones: Vec<Entity>,
    /// Member after member: what the plugin wrote into each `written` bone last frame. A
    /// bone still holding it was not animated since, and keeps its last animated pose as
    /// input (no feedback of the simulated pose into the next frame's input).
    pub(crate) wrote: Vec<Option<Transform>>,
    /// Each member's model-space entity (the parent of its root bone's entity).
    pub(crate) spaces: Vec<Option<Entity>>,
    /// Members held this frame (bad input): their bones are not written.
    pub(crate) held: Vec<bool>,
    /// Every member's written bones, each once; `shared_bones` once a bone came twice
    /// (two characters over one hierarchy): then one thread writes.
    pub(crate) bone_set: HashSet<Entity>,
    pub(crate) shared_bones: bool,
    /// Per member: how its bones are reached (tagged, or by entity).
    pub(crate) access: Vec<Access>,
    /// Per member: whether the tagged read pass took a bone into its `locals` since the
    /// last frame. A tagged member it did not is marked unchanged for the VRM crowd
    /// ([`VrmCrowd::mark_pose_unchanged`]): its pose is not read again.
    moved: Vec<bool>,
    /// Per member: its id in its bones' tags (stable while members move).
    uids: Vec<u32>,
    /// Id → member index (`u32::MAX`: a free id).
    member_of: Vec<u32>,
    /// Ids given back, for the next members.
    free_uids: Vec<u32>,
    /// Per joint: whether the crowd reads it, and the crowd's output slot of its rotation
    /// (or [`NOT_WRITTEN`]).
    roles: Vec<(bool, u32)>,
    /// The crowd's output slots per member.
    slots: usize,
    /// Every member's output rotations after the frame, member after member (filled for
    /// the tagged write pass).
    rotations: Vec<Quat>,
}

impl Kind {
    /// A crowd for `rig`, if its kind can run as one.
    pub(crate) fn new(rig: &Arc<CharacterRig>) -> Option<Result<Kind, Error>> {
        let kind = CrowdKind::of(rig)?;
        let make = || -> Result<Kind, Error> {
            let sk = Arc::new(rig.skeleton().clone());
            let n = sk.len();
            let (run, read, whole_pose) = match kind {
                CrowdKind::Vrm => {
                    let crowd = VrmCrowd::new(sk.clone(), Arc::new(rig.vrm().clone()))?;
                    let read = crowd.input_joints().to_vec();
                    let whole = rig.vrm().has_node_constraints();
                    (Run::Vrm(crowd), read, whole)
                }
                CrowdKind::Chains => {
                    let crowd = ChainCrowd::new(sk.clone(), Arc::new(rig.chains().clone()))?;
                    (Run::Chains(crowd), (0..n).collect(), false)
                }
            };
            let written = rig.simulated_joints().to_vec();
            let read_written = read.iter().map(|j| written.binary_search(j).ok()).collect();
            // Each joint's output slot: the crowd changes only these rotations (the last
            // slot of a joint wins, as in `write_rotations`).
            let mut slot = vec![NOT_WRITTEN; n];
            let rotated: Vec<usize> = match &run {
                Run::Vrm(c) => c.rig().links.iter().map(|l| l.joint).collect(),
                Run::Chains(c) => c.rig().rotator_joints().collect(),
            };
            for (k, &j) in rotated.iter().enumerate() {
                slot[j] = k as u32;
            }
            let roles = (0..n).map(|j| (read.contains(&j), slot[j])).collect();
            let slots = rotated.len();
            Ok(Kind {
                rig: rig.clone(),
                run,
                members: Vec::new(),
                locals: Vec::new(),
                roots: Vec::new(),
                read,
                whole_pose,
                scratch: Vec::new(),
                written,
                read_written,
                read_bones: Vec::new(),
                write_bones: Vec::new(),
                wrote: Vec::new(),
                spaces: Vec::new(),
                held: Vec::new(),
                bone_set: HashSet::new(),
                shared_bones: false,
                access: Vec::new(),
                moved: Vec::new(),
                uids: Vec::new(),
                member_of: Vec::new(),
                free_uids: Vec::new(),
                roles,
                slots,
                rotations: Vec::new(),
            })
        };
        Some(make())
    }

    fn joints(&self) -> usize {
        self.rig.skeleton().len()
    }

    /// Adds `entity`, whose joints' entities are `bones` and model space `space`;
    /// returns its index. It starts from its pose on its next frame.
    pub(crate) fn add(
        &mut self,
        entity: Entity,
        bones: &[Option<Entity>],
        space: Option<Entity>,
    ) -> Option<usize> {
        // Bind checked that every simulated joint has an entity; a kind's joints are the
        // same for every member.
        let write: Option<Vec<Entity>> = self.written.iter().map(|&j| bones[j]).collect();
        let write = write?;
        let i = match &mut self.run {
            Run::Vrm(c) => c.add(),
            Run::Chains(c) => c.add(),
        };
        debug_assert_eq!(i, self.members.len());
        self.members.push(entity);
        self.locals.extend_from_slice(self.rig.skeleton().rest());
        self.roots.push(Transform::IDENTITY);
        self.read_bones.extend(self.read.iter().map(|&j| bones[j]));
        for &e in &write {
            self.shared_bones |= !self.bone_set.insert(e);
        }
        self.write_bones.extend(write);
        self.wrote.extend(self.written.iter().map(|_| None));
        self.spaces.push(space);
        self.held.push(false);
        let uid = match self.free_uids.pop() {
            Some(u) => u,
            None => {
                self.member_of.push(u32::MAX);
                (self.member_of.len() - 1) as u32
            }
        };
        self.member_of[uid as usize] = i as u32;
        self.uids.push(uid);
        self.access.push(Access::Entities);
        self.moved.push(true);
        Some(i)
    }

    /// Member `i`'s bones with their tags (each bone the crowd reads or writes), or `None`
    /// when one entity stands for two joints, or the kind's output is a whole pose (VRM
    /// node constraints turn joints the crowd does not list).
    fn tags(&self, i: usize, bones: &[Option<Entity>]) -> Option<Vec<(Entity, CrowdBone)>> {
        if self.whole_pose {
            return None;
        }
        let mut tags = Vec::new();
        let mut seen = HashSet::new();
        for (j, (&(reads, slot), bone)) in self.roles.iter().zip(bones).enumerate() {
            let Some(e) = *bone else { continue };
            if !reads && slot == NOT_WRITTEN {
                continue;
            }
            if !seen.insert(e) {
                return None;
            }
            tags.push((
                e,
                CrowdBone {
                    kind: key(&self.rig),
                    uid: self.uids[i],
                    joint: j as u32,
                    reads,
                    slot,
                },
            ));
        }
        Some(tags)
    }

    /// Removes member `i`; the last member takes its index: returns that member's entity
    /// when one moved.
    pub(crate) fn swap_remove(&mut self, i: usize) -> Option<Entity> {
        let n = self.joints();
        let last = self.members.len() - 1;
        // The index exists (kept in step with the crowd's), so these cannot fail.
        let _ = match &mut self.run {
            Run::Vrm(c) => c.swap_remove(i),
            Run::Chains(c) => c.swap_remove(i),
        };
        let w = self.written.len();
        if !self.shared_bones {
            for e in &self.write_bones[i * w..(i + 1) * w] {
                self.bone_set.remove(e);
            }
        }
        self.members.swap_remove(i);
        self.roots.swap_remove(i);
        self.spaces.swap_remove(i);
        self.held.swap_remove(i);
        self.access.swap_remove(i);
        self.moved.swap_remove(i);
        let uid = self.uids.swap_remove(i);
        self.member_of[uid as usize] = u32::MAX;
        self.free_uids.push(uid);
        if i != last {
            self.member_of[self.uids[i] as usize] = i as u32;
        }
        swap_remove_run(&mut self.locals, n, i);
        swap_remove_run(&mut self.read_bones, self.read.len(), i);
        swap_remove_run(&mut self.write_bones, self.written.len(), i);
        swap_remove_run(&mut self.wrote, self.written.len(), i);
        (i != last).then(|| self.members[i])
    }

    /// Member `i` starts again from its pose on the next frame.
    pub(crate) fn reset(&mut self, i: usize) {
        let _ = match &mut self.run {
            Run::Vrm(c) => c.reset(i),
            Run::Chains(c) => c.reset(i),
        };
    }

    /// Every member advances by `dt`, the lane groups shared out over Bevy's compute
    /// task pool (rayon's own threads beside Bevy's made the step slower: the two pools
    /// fought for the cores); members whose input is bad are held (their state as before),
    /// marked in `self.held` and listed in `held`.
    pub(crate) fn frame(&mut self, dt: f32, held: &mut Vec<(usize, Error)>) {
        held.clear();
        self.held.fill(false);
        let n = self.joints();
        let (locals, roots) = (&self.locals, &self.roots);
        let input = |i: usize| CrowdPose {
            transform: roots[i],
            locals: &locals[i * n..(i + 1) * n],
        };
        let pool = ComputeTaskPool::get();
        let parts = parts(pool);
        if let Run::Vrm(c) = &mut self.run {
            // A tagged member none of whose bones changed gives the crowd last frame's
            // locals again (a member read by entity is read whole every frame).
            for (m, (&a, &moved)) in self.access.iter().zip(&self.moved).enumerate() {
                if a == Access::Tags && !moved {
                    let _ = c.mark_pose_unchanged(m);
                }
            }
        }
        if dt.is_finite() && dt >= 0.0 {
            // The frame runs (else the crowd forgets the marks, and the changes wait).
            self.moved.fill(false);
        }
        let result = match &mut self.run {
            Run::Vrm(c) => c.frame_parts(dt, input, parts, |jobs| {
                pool.scope(|s| jobs.for_each(|job| s.spawn(async move { job.run() })));
            }),
            Run::Chains(c) => c.frame_parts(dt, input, parts, |jobs| {
                pool.scope(|s| jobs.for_each(|job| s.spawn(async move { job.run() })));
            }),
        };
        if result.is_err() {
            match &self.run {
                Run::Vrm(c) => held.extend(c.held().map(|(i, e)| (i, e.clone()))),
                Run::Chains(c) => held.extend(c.held().map(|(i, e)| (i, e.clone()))),
            }
            for &(i, _) in held.iter() {
                self.held[i] = true;
            }
        }
    }

    /// Reads every member's world transform and animated bones into `roots` and `locals`,
    /// the members shared out over Bevy's compute task pool.
    pub(crate) fn read(&mut self, transforms: &Query<&BevyTransform>, parents: &Query<&ChildOf>) {
        let members = self.members.len();
        if members == 0 {
            return;
        }
        let (n, r, w) = (self.joints(), self.read.len(), self.written.len());
        let pool = ComputeTaskPool::get();
        let chunk = members.div_ceil(parts(pool));
        let (read, read_written) = (&self.read, &self.read_written);
        let (bones, wrote, spaces) = (&self.read_bones, &self.wrote, &self.spaces);
        let access = &self.access;
        let (locals, roots) = (&mut self.locals, &mut self.roots);
        pool.scope(|s| {
            for (c, (locals, roots)) in locals
                .chunks_mut(chunk * n)
                .zip(roots.chunks_mut(chunk))
                .enumerate()
            {
                let (a, b) = (c * chunk, c * chunk + roots.len());
                let part = Members {
                    read,
                    read_written,
                    bones: &bones[a * r..b * r],
                    wrote: &wrote[a * w..b * w],
                    spaces: &spaces[a..b],
                    access: &access[a..b],
                };
                s.spawn(async move { part.read(locals, roots, transforms, parents) });
            }
        });
    }

    /// The tagged read pass's view of this kind.
    pub(crate) fn read_view(&mut self) -> ReadView<'_> {
        ReadView {
            kind: key(&self.rig),
            joints: self.rig.skeleton().len(),
            member_of: &self.member_of,
            access: &self.access,
            locals: &mut self.locals,
            moved: &mut self.moved,
        }
    }

    /// Gathers the members' output rotations for the tagged write pass (when a member is
    /// tagged).
    pub(crate) fn gather_rotations(&mut self) {
        let tagged = self.access.contains(&Access::Tags);
        self.rotations.resize(
            if tagged {
                self.members.len() * self.slots
            } else {
                0
            },
            Quat::IDENTITY,
        );
        if tagged {
            // The lengths agree (members × slots), so this cannot fail.
            let _ = match &self.run {
                Run::Vrm(c) => c.rotations(&mut self.rotations),
                Run::Chains(c) => c.rotations(&mut self.rotations),
            };
        }
    }

    /// The tagged write pass's view of this kind (after [`Kind::gather_rotations`]).
    pub(crate) fn write_view(&self) -> WriteView<'_> {
        WriteView {
            kind: key(&self.rig),
            member_of: &self.member_of,
            access: &self.access,
            held: &self.held,
            slots: self.slots,
            rotations: &self.rotations,
        }
    }

    /// Members whose tags were inserted this frame reach their bones through them from the
    /// next one.
    pub(crate) fn tags_arrived(&mut self) {
        for a in &mut self.access {
            if *a == Access::Tagging {
                *a = Access::Tags;
            }
        }
    }

    /// Writes the simulated bones of every member not tagged (a tagged member's are written
    /// by the tagged pass) but a held member's (its bones keep their animated pose), the
    /// members shared out over Bevy's compute task pool.
    pub(crate) fn write(&mut self, transforms: &mut Query<&mut BevyTransform>) {
        let (members, w) = (self.members.len(), self.written.len());
        if members == 0 || w == 0 {
            return;
        }
        let pool = ComputeTaskPool::get();
        // Bones shared by two members (two characters over one hierarchy): one thread.
        let parts = if self.shared_bones { 1 } else { parts(pool) };
        let chunk = members.div_ceil(parts);
        let rest = self.rig.skeleton().rest();
        while self.scratch.len() < members.div_ceil(chunk) {
            self.scratch.push((rest.to_vec(), rest.to_vec()));
        }
        let out = Output {
            run: &self.run,
            whole_pose: self.whole_pose,
            locals: &self.locals,
            written: &self.written,
        };
        if self.access.iter().all(|&a| a == Access::Tags) {
            return;
        }
        let (bones, held, access) = (&self.write_bones, &self.held, &self.access);
        let transforms = &*transforms;
        pool.scope(|s| {
            for (c, (wrote, scratch)) in self
                .wrote
                .chunks_mut(chunk * w)
                .zip(self.scratch.iter_mut())
                .enumerate()
            {
                let first = c * chunk;
                let count = wrote.len() / w;
                let bones = &bones[first * w..(first + count) * w];
                let held = &held[first..first + count];
                let access = &access[first..first + count];
                let out = &out;
                s.spawn(async move {
                    for m in 0..count {
                        if held[m] || access[m] == Access::Tags {
                            continue;
                        }
                        let pose = out.pose(first + m, scratch);
                        let bones = &bones[m * w..(m + 1) * w];
                        let wrote = &mut wrote[m * w..(m + 1) * w];
                        for ((&j, &e), wrote) in out.written.iter().zip(bones).zip(wrote) {
                            // SAFETY: `transforms` is the step system's own
                            // `Query<&mut Transform>`, borrowed exclusively for this pass:
                            // nothing else reads or writes a `Transform` until the scope
                            // ends. Every entity of `write_bones` appears once in the kind
                            // (`shared_bones` is false, checked as members join; else one
                            // part does it all), each part writes only its own members'
                            // bones, and each `Mut` is dropped before the next: no two
                            // live references to one component.
                            #[allow(unsafe_code)]
                            let t = unsafe { transforms.get_unchecked(e) };
                            if let Ok(mut t) = t {
                                *t = to_bevy(&pose[j]);
                                *wrote = Some(pose[j]);
                            }
                        }
                    }
                });
            }
        });
    }
}

/// What a member's output pose is made of (shared by the write pass's parts).
struct Output<'k> {
    run: &'k Run,
    whole_pose: bool,
    locals: &'k [Transform],
    written: &'k [usize],
}

impl Output<'_> {
    /// Member `i`'s simulated local pose, in `scratch.0`: its animated locals with the
    /// solvers' rotations. Only the `written` joints are fresh; the others hold whatever
    /// an earlier member left (the write-back reads no other).
    fn pose<'s>(
        &self,
        i: usize,
        scratch: &'s mut (Vec<Transform>, Vec<Transform>),
    ) -> &'s [Transform] {
        let n = scratch.0.len();
        let input = &self.locals[i * n..(i + 1) * n];
        let (out, models) = scratch;
        if self.whole_pose {
            out.copy_from_slice(input);
        } else {
            // The crowd turns simulated joints only: their animated translation and scale
            // are the output's, and their rotation is written below.
            for &j in self.written {
                out[j] = input[j];
            }
        }
        let _ = match self.run {
            Run::Vrm(c) if self.whole_pose => c.write_pose(i, out, models),
            Run::Vrm(c) => c.write_rotations(i, out),
            Run::Chains(c) => c.write_rotations(i, out),
        };
        out
    }
}

/// A run of members as the read pass sees them (a share of a kind's flat lists).
struct Members<'k> {
    read: &'k [usize],
    read_written: &'k [Option<usize>],
    bones: &'k [Option<Entity>],
    wrote: &'k [Option<Transform>],
    spaces: &'k [Option<Entity>],
    access: &'k [Access],
}

impl Members<'_> {
    /// Each member's world transform into `roots` and its animated pose into `locals`
    /// (`read` joints only). A written bone that still holds what the plugin wrote last
    /// frame was not animated since (no clip drives it): it keeps its last animated pose.
    /// A bone without an entity stays at rest.
    fn read(
        &self,
        locals: &mut [Transform],
        roots: &mut [Transform],
        transforms: &Query<&BevyTransform>,
        parents: &Query<&ChildOf>,
    ) {
        let (n, r, w) = (
            locals.len() / roots.len(),
            self.read.len(),
            self.wrote.len() / roots.len(),
        );
        for (m, root) in roots.iter_mut().enumerate() {
            *root = world_of(self.spaces[m], transforms, parents);
            if self.access[m] == Access::Tags {
                // Its changed bones are read by the tagged pass.
                continue;
            }
            let locals = &mut locals[m * n..(m + 1) * n];
            let bones = &self.bones[m * r..(m + 1) * r];
            let wrote = &self.wrote[m * w..(m + 1) * w];
            for ((&j, bone), written) in self.read.iter().zip(bones).zip(self.read_written) {
                let Some(t) = bone.and_then(|e| transforms.get(e).ok()) else {
                    continue;
                };
                let t = to_tassel(t);
                if written.is_some_and(|k| wrote[k] == Some(t)) {
                    continue;
                }
                locals[j] = t;
            }
        }
    }
}

/// How many shares to cut a pass into: one per thread of the pool. (The step system
/// itself runs on one of them, and runs the scope's tasks while it waits; on two cores
/// Bevy gives the compute pool one thread unless the app asks for more.)
fn parts(pool: &ComputeTaskPool) -> usize {
    pool.thread_num().max(1)
}

/// Removes run `i` (of `len` items) from `v`, the last run taking its place.
fn swap_remove_run<T: Copy>(v: &mut Vec<T>, len: usize, i: usize) {
    if len == 0 {
        return;
    }
    let last = v.len() / len - 1;
    if i != last {
        v.copy_within(last * len..(last + 1) * len, i * len);
    }
    v.truncate(last * len);
}

/// Every crowd, by its compiled rig (the `Arc`'s address: the kind keeps it alive).
#[derive(Resource, Default)]
pub(crate) struct Crowds {
    pub(crate) kinds: HashMap<usize, Kind>,
    /// Where each crowd member is: kind and index.
    pub(crate) members: HashMap<Entity, (usize, usize)>,
    /// Kinds that cannot run as a crowd, or whose crowd failed to build (checked once).
    pub(crate) not_crowds: HashMap<usize, std::sync::Weak<CharacterRig>>,
    /// The bones tagged for a member (a [`CrowdBone`] each): a bone is tagged once.
    pub(crate) tagged: HashSet<Entity>,
}

/// The key of a compiled rig.
pub(crate) fn key(rig: &Arc<CharacterRig>) -> usize {
    Arc::as_ptr(rig) as usize
}

impl Crowds {
    /// Reads every tagged bone whose `Transform` changed since the step system last ran
    /// into its member's input (bones come kind after kind in table order: the view of the
    /// last kind met is kept, and looked up again only when the kind changes).
    pub(crate) fn read_tagged(
        &mut self,
        bones: &Query<(&CrowdBone, &BevyTransform), Changed<BevyTransform>>,
    ) {
        if self.kinds.is_empty() {
            return;
        }
        let mut view: Option<ReadView> = None;
        for (bone, t) in bones {
            if view.as_ref().map(|v| v.kind) != Some(bone.kind) {
                view = self.kinds.get_mut(&bone.kind).map(Kind::read_view);
            }
            if let Some(v) = view.as_mut() {
                v.take(bone, t);
            }
        }
    }

    /// Writes every tagged, written bone of a member that stepped, from its kind's output
    /// rotations, keeping the view of the last kind it met. On one thread: in the compute
    /// pool's threads (`par_iter_mut`) this pass took 0.56–0.86 ms a frame for 1 000
    /// avatars with two threads against 0.35–0.40 ms with one; as a plain loop it takes
    /// 0.24–0.43 ms with two threads for the solve (`bench/bevy_vrm1_vs_tassel -- 1000
    /// --avatar --threads 2`, two builds alternating, then four runs): a rotation store
    /// per bone is too little work to share.
    pub(crate) fn write_tagged(
        &mut self,
        bones: &mut Query<(&CrowdBone, &mut BevyTransform), With<WrittenBone>>,
    ) {
        if self.kinds.is_empty() {
            return;
        }
        for kind in self.kinds.values_mut() {
            kind.gather_rotations();
        }
        let kinds = &self.kinds;
        let mut view = None::<WriteView>;
        for (bone, mut t) in bones.iter_mut() {
            if view.as_ref().map(|v| v.kind) != Some(bone.kind) {
                view = kinds.get(&bone.kind).map(Kind::write_view);
            }
            if let Some(r) = view.as_ref().and_then(|v| v.rotation(bone)) {
                t.rotation = r;
            }
        }
    }

    /// Adds `entity` (a character of kind `rig`) to its kind's crowd when the kind runs as
    /// one; returns its index, or `None` (the character steps on its own).
    pub(crate) fn join(
        &mut self,
        entity: Entity,
        rig: &Arc<CharacterRig>,
        bones: &[Option<Entity>],
        space: Option<Entity>,
        commands: &mut Commands,
    ) -> Option<usize> {
        let k = key(rig);
        if self
            .not_crowds
            .get(&k)
            .is_some_and(|w| w.strong_count() > 0)
        {
            return None;
        }
        if !self.kinds.contains_key(&k) {
            match Kind::new(rig) {
                Some(Ok(kind)) => {
                    self.kinds.insert(k, kind);
                }
                _ => {
                    self.not_crowds.retain(|_, w| w.strong_count() > 0);
                    self.not_crowds.insert(k, Arc::downgrade(rig));
                    return None;
                }
            }
        }
        let kind = self.kinds.get_mut(&k)?;
        let Some(i) = kind.add(entity, bones, space) else {
            if kind.members.is_empty() {
                self.kinds.remove(&k);
            }
            return None;
        };
        self.members.insert(entity, (k, i));
        // Its bones get their tags unless one is another member's too.
        if let Some(tags) = kind.tags(i, bones) {
            if tags.iter().all(|(e, _)| !self.tagged.contains(e)) {
                for (e, tag) in tags {
                    self.tagged.insert(e);
                    if tag.slot == NOT_WRITTEN {
                        commands.entity(e).try_insert(tag);
                    } else {
                        commands.entity(e).try_insert((tag, WrittenBone));
                    }
                }
                kind.access[i] = Access::Tagging;
            }
        }
        Some(i)
    }

    /// The kind and index of crowd member `entity`.
    pub(crate) fn kind_of(&mut self, entity: Entity) -> Option<(&mut Kind, usize)> {
        let &(k, i) = self.members.get(&entity)?;
        Some((self.kinds.get_mut(&k)?, i))
    }

    /// Removes `entity` from its crowd, if it is in one: returns the member that took its
    /// index (entity and new index), for its component to follow. A kind left empty is
    /// dropped (and with it the crowd's hold on the compiled rig).
    pub(crate) fn leave(
        &mut self,
        entity: Entity,
        commands: &mut Commands,
    ) -> Option<(Entity, usize)> {
        let (k, i) = self.members.remove(&entity)?;
        let kind = self.kinds.get_mut(&k)?;
        if kind.access[i] != Access::Entities {
            let (r, w) = (kind.read.len(), kind.written.len());
            let read = kind.read_bones[i * r..(i + 1) * r].iter().flatten();
            for &e in read.chain(&kind.write_bones[i * w..(i + 1) * w]) {
                if self.tagged.remove(&e) {
                    commands.entity(e).try_remove::<(CrowdBone, WrittenBone)>();
                }
            }
        }
        let moved = kind.swap_remove(i);
        if kind.members.is_empty() {
            self.kinds.remove(&k);
        }
        let moved = moved?;
        if let Some(m) = self.members.get_mut(&moved) {
            m.1 = i;
        }
        Some((moved, i))
    }
}
