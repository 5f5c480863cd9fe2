//! VRM spring bones in SIMD lanes, beside the scalar update (`dynamics/vrm/job.rs`, the
//! readable reference every lane path is tested against bit for bit):
//!
//! - `springs.rs`: one character's springs side by side, up to [`crate::lanes::LANES`]
//!   at a time ([`super::VrmJob`] runs it unless [`crate::lanes::SimdUse::Scalar`]);
//! - `pack.rs` and `frame.rs`: a lane group of characters, one per lane, for
//!   [`crate::crowd::VrmCrowd`];
//! - `contact.rs`: the specification's collision per lane, shared by both.

pub(crate) mod contact;
mod frame;
mod pack;
pub(crate) mod springs;

pub(crate) use frame::Ctx;
pub(crate) use pack::{LaneState, Pack, Plan, Scratch};
