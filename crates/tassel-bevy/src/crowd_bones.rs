//! Crowd members' bones read and written by walking them, not by looking each one up.
//!
//! A member whose bones are its own (no other member reads or writes one of them, and its
//! kind's output is rotations only: no VRM node constraints) tags each bone it reads or
//! writes with a [`CrowdBone`] (its kind, the member's stable id, the joint, the crowd's
//! output slot of its rotation), and each bone it writes also with a [`WrittenBone`]. The
//! read pass walks the tagged bones whose `Transform` changed since the step system last
//! ran (Bevy's change ticks: the plugin's own writes are not changes to it, so a bone no
//! animation drives keeps its last animated pose as input, as the per-entity path's
//! comparison with what the plugin wrote does); the write pass walks the written bones on
//! one thread and sets each one's rotation from the crowd's output, gathered once per
//! frame member after member. Both walk Bevy's tables in order, and the read touches
//! nothing of a bone no animation moved. A VRM member none of whose bones changed is
//! marked unchanged for the crowd, which then reuses the pose its lane group kept instead
//! of reading the member's input again (`VrmCrowd::mark_pose_unchanged`).
//!
//! The tags arrive with the commands applied after the step system, so a member reads and
//! writes through its entities on the frame it joins (which also reads its whole pose,
//! changed or not), then through its tags. A member sharing a bone with another one
//! (two characters over one hierarchy) keeps the per-entity path.

use crate::convert::to_tassel;
use bevy::ecs::prelude::*;
use bevy::prelude::{Quat, Transform as BevyTransform};
use tassel::Transform;

/// No written slot: the bone is read only.
pub(crate) const NOT_WRITTEN: u32 = u32::MAX;

/// A crowd member's bone: what the tagged read and write passes need to find its slot.
#[derive(Component, Clone, Copy, Debug)]
pub(crate) struct CrowdBone {
    /// The member's kind ([`crate::crowd::key`] of its compiled rig).
    pub(crate) kind: usize,
    /// The member's id in its kind (its index follows through `Kind::member_of`).
    pub(crate) uid: u32,
    /// The joint this bone is.
    pub(crate) joint: u32,
    /// Whether the crowd reads this joint's animated pose.
    pub(crate) reads: bool,
    /// The crowd's output slot of its rotation, or [`NOT_WRITTEN`].
    pub(crate) slot: u32,
}

/// A tagged bone the crowd writes (beside its [`CrowdBone`]): the write pass walks only
/// these.
#[derive(Component, Clone, Copy, Debug)]
pub(crate) struct WrittenBone;

/// How a crowd member's bones are reached.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(crate) enum Access {
    /// By entity lookups, always (a bone shared with another member).
    Entities,
    /// By entity lookups this frame; its tags are being inserted.
    Tagging,
    /// By its tagged bones.
    Tags,
}

/// One kind's buffers as the tagged read pass fills them.
pub(crate) struct ReadView<'k> {
    pub(crate) kind: usize,
    /// Joints per member.
    pub(crate) joints: usize,
    pub(crate) member_of: &'k [u32],
    pub(crate) access: &'k [Access],
    pub(crate) locals: &'k mut [Transform],
    /// Per member: a bone was taken into its `locals` since the last frame.
    pub(crate) moved: &'k mut [bool],
}

/// One kind's output as the tagged write pass copies it.
pub(crate) struct WriteView<'k> {
    pub(crate) kind: usize,
    pub(crate) member_of: &'k [u32],
    pub(crate) access: &'k [Access],
    pub(crate) held: &'k [bool],
    /// Output slots per member.
    pub(crate) slots: usize,
    /// Every member's output rotations, member after member.
    pub(crate) rotations: &'k [Quat],
}

impl ReadView<'_> {
    /// Takes the animated transform `t` of tagged bone `bone` (of this view's kind) into its
    /// member's `locals`, when the member reads through its tags.
    #[inline]
    pub(crate) fn take(&mut self, bone: &CrowdBone, t: &BevyTransform) {
        let Some(&m) = self.member_of.get(bone.uid as usize) else {
            return;
        };
        let m = m as usize;
        if bone.reads && self.access.get(m) == Some(&Access::Tags) {
            self.locals[m * self.joints + bone.joint as usize] = to_tassel(t);
            self.moved[m] = true;
        }
    }
}

impl WriteView<'_> {
    /// The rotation tagged, written bone `bone` (of this view's kind) gets: its member's
    /// output, when the member writes through its tags and stepped (was not held). Only
    /// the rotation: a crowd turns the bones it writes, and their translation and scale
    /// are already this frame's animated ones (read from them, or unchanged since), which
    /// is what the per-entity path writes back with the rotation.
    #[inline]
    pub(crate) fn rotation(&self, bone: &CrowdBone) -> Option<Quat> {
        if bone.slot == NOT_WRITTEN {
            return None;
        }
        let m = *self.member_of.get(bone.uid as usize)? as usize;
        if self.access.get(m) != Some(&Access::Tags) || self.held[m] {
            return None;
        }
        self.rotations
            .get(m * self.slots + bone.slot as usize)
            .copied()
    }
}
