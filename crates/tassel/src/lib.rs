//! # Tassel
//!
//! Secondary motion for game characters — hair, tails, skirts, ropes — after the animated
//! pose, frame-rate independent, collision-aware and deterministic.
//!
//! Entry points:
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

pub use error::{Error, Result};
pub use instance::CharacterSim;
pub use math::Transform;
pub use pose::{LocalToModelJob, ModelToLocalJob, Pose};
pub use skeleton::{Skeleton, SkeletonBuilder, MAX_JOINTS, NO_PARENT};
