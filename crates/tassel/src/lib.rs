//! # Tassel
//!
//! Secondary motion for game characters — hair, tails, skirts, ropes — after the animated
//! pose, frame-rate independent, collision-aware and deterministic.
//!
//! Entry points:
//! - [`CharacterSim`]: one character's frame; [`CharacterRig`]: a compiled kind of
//!   character, shared by many (`Arc`).
//! - [`Skeleton`], [`SkeletonBuilder`], [`Pose`], [`LocalToModelJob`], [`ModelToLocalJob`]:
//!   the character.
//! - [`anim::Clip`]: animation clips sampled by the glTF rules.
//! - [`dynamics::RigSettings`] (a TOML rig file), [`dynamics::chain::ChainRig`],
//!   [`dynamics::chain::ChainState`], [`dynamics::chain::ChainJob`]: bone chains.
//! - [`collide`]: collider shapes and point queries.
//! - [`builtin`]: an embedded demo character with procedural clips.
//!
//! The core does no file I/O.

pub mod anim;
pub mod builtin;
mod character_rig;
pub mod collide;
pub mod controller;
pub mod crowd;
pub mod dynamics;
mod error;
mod instance;
pub mod limits;
pub mod math;
mod pose;
pub mod rng;
mod skeleton;

pub use character_rig::CharacterRig;
pub use error::{Error, Result};
/// The math library Tassel's API speaks (glam 0.32), re-exported so a user needs no
/// second, possibly different, version.
pub use glam;
pub use instance::CharacterSim;
pub use math::Transform;
pub use pose::{LocalToModelJob, ModelToLocalJob, Pose};
pub use skeleton::{Skeleton, SkeletonBuilder, MAX_JOINTS, NO_PARENT};
