//! The VRM crowd's lane groups: what it needs of each link ([`Plan`], precomputed with
//! the scalar code's own operations), a lane group's state ([`Pack`]) and one thread's
//! working buffers ([`Scratch`]).

use super::contact::Placed;
use crate::dynamics::path::CharacterPath;
use crate::dynamics::vrm::{LinkLimit, VrmRig, VrmShape};
use crate::error::{Error, Result};
use crate::lanes::{Trs, F, LANES, Q, V3};
use crate::math::{normalize_or, Transform};
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// What the crowd needs of one link, precomputed with the scalar code's own operations.
#[derive(Debug, Clone)]
pub(crate) struct LinkPlan {
    pub(crate) slot: usize,
    pub(crate) center: Option<usize>,
    pub(crate) tail_slot: Option<usize>,
    pub(crate) tail_local: Vec3,
    pub(crate) rest_local: Transform,
    /// `rest_local.rotation * bone_axis`.
    pub(crate) rest_bone: Vec3,
    pub(crate) bone_axis: Vec3,
    /// `normalize_or(bone_axis, Y)`, and its half-turn quaternion.
    pub(crate) arc_from: Vec3,
    pub(crate) half_turn: Quat,
    /// `1 − drag_force`.
    pub(crate) keep: f32,
    pub(crate) hit_radius: f32,
    pub(crate) colliders: std::ops::Range<usize>,
    /// The link's swing limit, applied lane by lane with the scalar code.
    pub(crate) limit: Option<LinkLimit>,
}

/// The joints a crowd computes (every link, tail, centre and collider joint and their
/// ancestors), in skeleton order, and the links on them.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    pub(crate) joints: Vec<usize>,
    pub(crate) parent: Vec<Option<usize>>,
    /// The link on each slot, if any.
    pub(crate) link_at: Vec<Option<usize>>,
    /// Slots whose model a link's rotation can change (a link or below one).
    pub(crate) affected: Vec<bool>,
    /// Slots whose animated model a specification step reads before its update writes
    /// it, or never writes: every slot not affected, a root link (its own model), a
    /// centre, a collider's joint, and the ancestors of all these (their models are
    /// composed from the parent's). The others' animated models are overwritten unread.
    pub(crate) read_animated: Vec<bool>,
    /// Skeleton joints not in `joints` (their input is checked, not used).
    pub(crate) unplanned: Vec<usize>,
    pub(crate) links: Vec<LinkPlan>,
    pub(crate) colliders: Vec<(usize, VrmShape)>,
}

impl Plan {
    pub(crate) fn new(sk: &Skeleton, rig: &VrmRig) -> Result<Plan> {
        let n = sk.len();
        let mut needed = vec![false; n];
        let mark = |j: usize, needed: &mut Vec<bool>| {
            let mut k = Some(j);
            while let Some(x) = k {
                if needed[x] {
                    break;
                }
                needed[x] = true;
                k = sk.parent(x);
            }
        };
        for l in &rig.links {
            mark(l.joint, &mut needed);
            if let Some(t) = l.tail_joint {
                mark(t, &mut needed);
            }
            if let Some(c) = l.center {
                mark(c, &mut needed);
            }
        }
        for (j, _) in &rig.colliders {
            mark(*j, &mut needed);
        }
        let joints: Vec<usize> = (0..n).filter(|&j| needed[j]).collect();
        let unplanned: Vec<usize> = (0..n).filter(|&j| !needed[j]).collect();
        let mut slot_of = vec![usize::MAX; n];
        for (s, &j) in joints.iter().enumerate() {
            slot_of[j] = s;
        }
        let parent: Vec<Option<usize>> = joints
            .iter()
            .map(|&j| sk.parent(j).map(|p| slot_of[p]))
            .collect();
        let mut link_at = vec![None; joints.len()];
        let mut links = Vec::with_capacity(rig.links.len());
        for (i, l) in rig.links.iter().enumerate() {
            if let Some(c) = l.center {
                if c > l.joint {
                    return Err(Error::InvalidParameter(format!(
                        "crowd: spring joint '{}' has its centre '{}' after it in the \
                         skeleton; a crowd needs the centre to be an ancestor or earlier joint",
                        sk.name(l.joint),
                        sk.name(c)
                    )));
                }
            }
            let slot = slot_of[l.joint];
            link_at[slot] = Some(i);
            let arc_from = normalize_or(l.bone_axis, Vec3::Y);
            let o = arc_from.any_orthonormal_vector();
            links.push(LinkPlan {
                slot,
                center: l.center.map(|c| slot_of[c]),
                tail_slot: l.tail_joint.map(|t| slot_of[t]),
                tail_local: l.tail_local,
                rest_local: l.rest_local,
                rest_bone: l.rest_local.rotation * l.bone_axis,
                bone_axis: l.bone_axis,
                arc_from,
                half_turn: Quat::from_xyzw(o.x, o.y, o.z, 0.0),
                keep: 1.0 - l.drag_force,
                hit_radius: l.hit_radius,
                colliders: l.colliders.clone(),
                limit: l.limit,
            });
        }
        let mut affected = vec![false; joints.len()];
        for s in 0..joints.len() {
            affected[s] = link_at[s].is_some() || parent[s].is_some_and(|p| affected[p]);
        }
        let colliders: Vec<(usize, VrmShape)> = rig
            .colliders
            .iter()
            .map(|&(j, shape)| (slot_of[j], shape))
            .collect();
        let mut read_animated: Vec<bool> = (0..joints.len())
            .map(|s| !affected[s] || (link_at[s].is_some() && parent[s].is_none()))
            .collect();
        for lp in &links {
            if let Some(c) = lp.center {
                read_animated[c] = true;
            }
        }
        for &(slot, _) in &colliders {
            read_animated[slot] = true;
        }
        // Parents come before their children, so one pass from the end reaches the roots.
        for s in (0..joints.len()).rev() {
            if read_animated[s] {
                if let Some(p) = parent[s] {
                    read_animated[p] = true;
                }
            }
        }
        Ok(Plan {
            joints,
            parent,
            link_at,
            affected,
            read_animated,
            unplanned,
            links,
            colliders,
        })
    }
}

/// A lane group: the state of up to [`LANES`] characters, one per lane.
#[derive(Debug, Clone)]
pub(crate) struct Pack {
    /// Characters in use (the rest of the lanes run on the rest pose, unseen).
    pub(crate) count: usize,
    pub(crate) current_tail: Vec<V3>,
    pub(crate) prev_tail: Vec<V3>,
    pub(crate) length: Vec<F>,
    pub(crate) stale_tail: Vec<V3>,
    pub(crate) rotation: Vec<Q>,
    /// The rotations the last frame wrote (fixed mode: the last step's, or an output
    /// step's).
    pub(crate) out_rotation: Vec<Q>,
    /// Fixed mode: last frame's animated locals (per plan slot) and each character's
    /// recent transforms, and the time not yet stepped.
    pub(crate) prev_locals: Vec<Trs>,
    /// Fixed mode: `prev_locals` holds last frame's input itself, every lane (no reset
    /// wrote rest rotations into it, no character was held or moved in since).
    pub(crate) prev_is_input: bool,
    /// The characters whose caller promised this frame's animated locals are last
    /// frame's ([`crate::crowd::VrmCrowd::mark_pose_unchanged`]); cleared by every frame.
    pub(crate) unchanged: [bool; LANES],
    pub(crate) paths: Vec<CharacterPath>,
    pub(crate) accumulator: [f32; LANES],
    pub(crate) prev_component: Trs,
    pub(crate) needs_reset: [bool; LANES],
    pub(crate) resets: [u64; LANES],
    /// The characters (crowd indices) whose input was bad in the last frame, and why:
    /// their lanes were held (their state as before the frame).
    pub(crate) held: Vec<(usize, Error)>,
}

impl Pack {
    pub(crate) fn new(links: usize, slots: usize) -> Pack {
        let zero = V3::splat(Vec3::ZERO);
        let id = Q::splat(Quat::IDENTITY);
        Pack {
            count: 0,
            current_tail: vec![zero; links],
            prev_tail: vec![zero; links],
            length: vec![F::splat(0.0); links],
            stale_tail: vec![zero; links],
            rotation: vec![id; links],
            out_rotation: vec![id; links],
            prev_locals: vec![Trs::splat(&Transform::IDENTITY); slots],
            prev_is_input: false,
            unchanged: [false; LANES],
            paths: vec![CharacterPath::default(); LANES],
            accumulator: [0.0; LANES],
            prev_component: Trs::splat(&Transform::IDENTITY),
            needs_reset: [true; LANES],
            resets: [0; LANES],
            held: Vec::new(),
        }
    }
}

/// One character's state, taken out of its lane (to move it to another).
#[derive(Debug, Clone)]
pub(crate) struct LaneState {
    pub(crate) current_tail: Vec<Vec3>,
    pub(crate) prev_tail: Vec<Vec3>,
    pub(crate) length: Vec<f32>,
    pub(crate) stale_tail: Vec<Vec3>,
    pub(crate) rotation: Vec<Quat>,
    pub(crate) out_rotation: Vec<Quat>,
    pub(crate) prev_locals: Vec<Transform>,
    pub(crate) path: CharacterPath,
    pub(crate) accumulator: f32,
    pub(crate) prev_component: Transform,
    pub(crate) needs_reset: bool,
    pub(crate) resets: u64,
}

impl Pack {
    pub(crate) fn lane(&self, l: usize) -> LaneState {
        LaneState {
            current_tail: self.current_tail.iter().map(|v| v.get(l)).collect(),
            prev_tail: self.prev_tail.iter().map(|v| v.get(l)).collect(),
            length: self.length.iter().map(|v| v.get(l)).collect(),
            stale_tail: self.stale_tail.iter().map(|v| v.get(l)).collect(),
            rotation: self.rotation.iter().map(|q| q.get(l)).collect(),
            out_rotation: self.out_rotation.iter().map(|q| q.get(l)).collect(),
            prev_locals: self.prev_locals.iter().map(|t| t.get(l)).collect(),
            path: self.paths[l],
            accumulator: self.accumulator[l],
            prev_component: self.prev_component.get(l),
            needs_reset: self.needs_reset[l],
            resets: self.resets[l],
        }
    }

    pub(crate) fn set_lane(&mut self, l: usize, s: &LaneState) {
        for (d, v) in self.current_tail.iter_mut().zip(&s.current_tail) {
            d.set(l, *v);
        }
        for (d, v) in self.prev_tail.iter_mut().zip(&s.prev_tail) {
            d.set(l, *v);
        }
        for (d, v) in self.length.iter_mut().zip(&s.length) {
            d.0[l] = *v;
        }
        for (d, v) in self.stale_tail.iter_mut().zip(&s.stale_tail) {
            d.set(l, *v);
        }
        for (d, q) in self.rotation.iter_mut().zip(&s.rotation) {
            d.set(l, *q);
        }
        for (d, q) in self.out_rotation.iter_mut().zip(&s.out_rotation) {
            d.set(l, *q);
        }
        for (d, t) in self.prev_locals.iter_mut().zip(&s.prev_locals) {
            d.set(l, t);
        }
        // Another character's kept pose (or one put back after a held frame): the lane's
        // input of last frame is not known to be it.
        self.prev_is_input = false;
        self.unchanged[l] = false;
        self.paths[l] = s.path;
        self.accumulator[l] = s.accumulator;
        self.prev_component.set(l, &s.prev_component);
        self.needs_reset[l] = s.needs_reset;
        self.resets[l] = s.resets;
    }
}

/// One thread's working buffers.
#[derive(Debug, Clone)]
pub(crate) struct Scratch {
    pub(crate) locals: Vec<Trs>,
    pub(crate) models: Vec<Trs>,
    pub(crate) reset_models: Vec<Trs>,
    pub(crate) step_locals: Vec<Trs>,
    pub(crate) step_models: Vec<Trs>,
    /// Fixed mode's output step: the state it starts from, put back after it.
    pub(crate) kept_current: Vec<V3>,
    pub(crate) kept_prev: Vec<V3>,
    pub(crate) kept_rotation: Vec<Q>,
    pub(crate) placed: Vec<Placed>,
    pub(crate) full_locals: Vec<Transform>,
    pub(crate) full_models: Vec<Transform>,
    pub(crate) component: Trs,
    /// This group's `locals` are its kept pose, copied (its input was marked unchanged):
    /// the pose need not be kept again.
    pub(crate) reused: bool,
}

impl Scratch {
    pub(crate) fn new(plan: &Plan, joints: usize) -> Scratch {
        let id = Trs::splat(&Transform::IDENTITY);
        let zero = V3::splat(Vec3::ZERO);
        Scratch {
            locals: vec![id; plan.joints.len()],
            models: vec![id; plan.joints.len()],
            reset_models: vec![id; plan.joints.len()],
            step_locals: vec![id; plan.joints.len()],
            step_models: vec![id; plan.joints.len()],
            kept_current: vec![zero; plan.links.len()],
            kept_prev: vec![zero; plan.links.len()],
            kept_rotation: vec![Q::splat(Quat::IDENTITY); plan.links.len()],
            placed: vec![
                Placed {
                    a: zero,
                    b: zero,
                    mid: zero,
                    half: F::splat(0.0),
                };
                plan.colliders.len()
            ],
            full_locals: vec![Transform::IDENTITY; joints],
            full_models: vec![Transform::IDENTITY; joints],
            component: id,
            reused: false,
        }
    }
}
