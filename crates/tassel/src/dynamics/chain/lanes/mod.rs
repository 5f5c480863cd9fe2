//! Bone chains in SIMD lanes: the chain solver's lane step beside its scalar step
//! ([`super::step`], the readable reference every lane path is tested against bit for
//! bit).
//!
//! A lane is one chain: of one character each ([`crate::crowd::ChainCrowd`], a lane group
//! of [`crate::lanes::LANES`] characters with the same rig) or a *twin* of one character
//! (hair strands, skirt chains: [`twins`], which [`super::ChainJob`] runs unless
//! [`crate::lanes::SimdUse::Scalar`]). Both run the same lane-group frame:
//!
//! - `pack.rs`: a lane group's state ([`Pack`]) and one thread's working buffers
//!   ([`Scratch`]);
//! - `frame.rs`: the frame of a lane group ([`Ctx`]): the input checks, the model pose,
//!   the animated targets and placed colliders, the characters' paths and motion, the
//!   time modes, the write-back of rotations; per character in scalar code where that is
//!   the job's own function;
//! - `step.rs`: one solver step and the output pass, per lane, with a character's own
//!   branches (a reset, a step count, a contact) as lane masks.

mod frame;
mod pack;
pub(crate) mod step;
pub(crate) mod twins;

pub(crate) use frame::{any_planar, Ctx};
pub(crate) use pack::{LaneState, Pack, Scratch};
pub(crate) use step::LaneShape;
