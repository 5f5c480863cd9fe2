//! Characters of one kind stepped together: a [`VrmCrowd`] or a [`ChainCrowd`] per compiled
//! rig ([`CrowdKind::of`]), with the characters' animated input and the simulated output in
//! flat buffers, one slot per character.

use bevy::ecs::prelude::*;
use bevy::platform::collections::HashMap;
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
    /// Scratch for `write_pose` (whole-pose kinds).
    pub(crate) scratch_locals: Vec<Transform>,
    pub(crate) scratch_models: Vec<Transform>,
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
            Ok(Kind {
                rig: rig.clone(),
                run,
                members: Vec::new(),
                locals: Vec::new(),
                roots: Vec::new(),
                read,
                whole_pose,
                scratch_locals: sk.rest().to_vec(),
                scratch_models: sk.rest().to_vec(),
            })
        };
        Some(make())
    }

    fn joints(&self) -> usize {
        self.rig.skeleton().len()
    }

    /// Adds `entity`; returns its index. It starts from its pose on its next frame.
    pub(crate) fn add(&mut self, entity: Entity) -> usize {
        let i = match &mut self.run {
            Run::Vrm(c) => c.add(),
            Run::Chains(c) => c.add(),
        };
        debug_assert_eq!(i, self.members.len());
        self.members.push(entity);
        self.locals.extend_from_slice(self.rig.skeleton().rest());
        self.roots.push(Transform::IDENTITY);
        i
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
        self.members.swap_remove(i);
        self.roots.swap_remove(i);
        if i != last {
            self.locals.copy_within(last * n..(last + 1) * n, i * n);
        }
        self.locals.truncate(last * n);
        (i != last).then(|| self.members[i])
    }

    /// Member `i`'s animated local pose (every joint).
    pub(crate) fn locals_mut(&mut self, i: usize) -> &mut [Transform] {
        let n = self.joints();
        &mut self.locals[i * n..(i + 1) * n]
    }

    /// Member `i` starts again from its pose on the next frame.
    pub(crate) fn reset(&mut self, i: usize) {
        let _ = match &mut self.run {
            Run::Vrm(c) => c.reset(i),
            Run::Chains(c) => c.reset(i),
        };
    }

    /// Every member advances by `dt`; members whose input is bad are held (their state as
    /// before) and listed in `held`.
    pub(crate) fn frame(&mut self, dt: f32, held: &mut Vec<(usize, Error)>) {
        held.clear();
        let n = self.joints();
        let (locals, roots) = (&self.locals, &self.roots);
        let input = |i: usize| CrowdPose {
            transform: roots[i],
            locals: &locals[i * n..(i + 1) * n],
        };
        let result = match &mut self.run {
            Run::Vrm(c) => c.frame(dt, input),
            Run::Chains(c) => c.frame(dt, input),
        };
        if result.is_err() {
            match &self.run {
                Run::Vrm(c) => held.extend(c.held().map(|(i, e)| (i, e.clone()))),
                Run::Chains(c) => held.extend(c.held().map(|(i, e)| (i, e.clone()))),
            }
        }
    }

    /// Member `i`'s simulated local pose: its animated locals with the solvers' rotations.
    /// Only the joints of `written` (simulated joints, ascending) are fresh; the others
    /// hold whatever an earlier member left (the write-back reads no other).
    pub(crate) fn output(&mut self, i: usize, written: &[(usize, Entity)]) -> &[Transform] {
        let n = self.joints();
        let input = &self.locals[i * n..(i + 1) * n];
        if self.whole_pose {
            self.scratch_locals.copy_from_slice(input);
        } else {
            // The crowd turns simulated joints only: their animated translation and scale
            // are the output's, and their rotation is written below.
            for &(j, _) in written {
                self.scratch_locals[j] = input[j];
            }
        }
        let out = &mut self.scratch_locals;
        let _ = match &self.run {
            Run::Vrm(c) if self.whole_pose => c.write_pose(i, out, &mut self.scratch_models),
            Run::Vrm(c) => c.write_rotations(i, out),
            Run::Chains(c) => c.write_rotations(i, out),
        };
        &self.scratch_locals
    }
}

/// Every crowd, by its compiled rig (the `Arc`'s address: the kind keeps it alive).
#[derive(Resource, Default)]
pub(crate) struct Crowds {
    pub(crate) kinds: HashMap<usize, Kind>,
    /// Where each crowd member is: kind and index.
    pub(crate) members: HashMap<Entity, (usize, usize)>,
    /// Kinds that cannot run as a crowd, or whose crowd failed to build (checked once).
    pub(crate) not_crowds: HashMap<usize, std::sync::Weak<CharacterRig>>,
}

/// The key of a compiled rig.
pub(crate) fn key(rig: &Arc<CharacterRig>) -> usize {
    Arc::as_ptr(rig) as usize
}

impl Crowds {
    /// Adds `entity` (a character of kind `rig`) to its kind's crowd when the kind runs as
    /// one; returns its index, or `None` (the character steps on its own).
    pub(crate) fn join(&mut self, entity: Entity, rig: &Arc<CharacterRig>) -> Option<usize> {
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
        let i = kind.add(entity);
        self.members.insert(entity, (k, i));
        Some(i)
    }

    /// Removes `entity` from its crowd, if it is in one: returns the member that took its
    /// index (entity and new index), for its component to follow. A kind left empty is
    /// dropped (and with it the crowd's hold on the compiled rig).
    pub(crate) fn leave(&mut self, entity: Entity) -> Option<(Entity, usize)> {
        let (k, i) = self.members.remove(&entity)?;
        let kind = self.kinds.get_mut(&k)?;
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
