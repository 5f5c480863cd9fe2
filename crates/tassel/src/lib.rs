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
//! - [`crowd::VrmCrowd`], [`crowd::ChainCrowd`]: many characters of one kind advanced
//!   together, bit for bit as [`CharacterSim`] would advance each.
//! - [`lanes`]: the SIMD lane types below the solvers ([`lanes::SimdUse`] chooses the
//!   code that runs; every choice gives the same bits).
//!
//! Layers, lowest first: [`math`] and [`limits`] → [`lanes`] → [`collide`], [`anim`],
//! [`controller`] → each solver in [`dynamics`] (its readable scalar step and its lane
//! step side by side) → the character ([`CharacterRig`], [`CharacterSim`]) → [`crowd`].
//! A lower layer never imports a higher one.
//!
//! The core does no file I/O.
//!
//! One character, one frame at a time:
//!
//! ```
//! use tassel::{builtin, CharacterSim, Transform};
//!
//! let character = builtin::character(); // or tassel_gltf::load(path) and a rig file
//! let mut sim = CharacterSim::new(character.skeleton.clone(), &character.rig)?;
//! let animated = character.skeleton.rest().to_vec(); // each frame: your animated local pose
//! let joints = sim.simulated_joints().to_vec(); // the bones the solvers move
//! for frame in 0..120 {
//!     let at = Transform::from_translation(tassel::glam::Vec3::X * 0.02 * frame as f32);
//!     let dt = if frame == 0 { 0.0 } else { 1.0 / 60.0 }; // frame 0 places the solvers
//!     let pose = sim.frame(&animated, at, dt)?; // the simulated bones written in
//!     for &j in &joints {
//!         let _local = pose.locals[j]; // copy these back to your engine's bones
//!     }
//! }
//! # Ok::<(), tassel::Error>(())
//! ```
//!
//! ## Units and conventions
//! - Lengths in metres, times in seconds, Y up, right-handed (glTF's frame).
//! - **Angles in degrees** wherever a person types or reads one: rig files and every
//!   settings struct (`limit_angle`, `teleport_angle`, `teleport_rotation`, the
//!   controller's `max_climb_angle` and `min_slide_angle`), [`controller::Movement::slope_angle`],
//!   [`controller::LevelShape::ramp_with_angle`] and particle angle constraints. Rotations
//!   themselves are glam `Quat`s.
//! - **Stepping**: [`dynamics::SimMode`] is the one switch for a character; its default is
//!   `Fixed` (frame-rate independent), like [`dynamics::chain::TimeMode`] and
//!   [`dynamics::vrm::VrmMode`]. `Spec` and `ThreeVrm` stay available by name for parity
//!   with the VRM specification and three-vrm.
//! - The first frame of a run is stepped with `dt = 0` (see [`CharacterSim`]).

pub mod anim;
mod animated;
pub mod builtin;
mod character_rig;
pub mod collide;
pub mod controller;
pub mod crowd;
pub mod dynamics;
mod error;
mod instance;
pub mod lanes;
pub mod limits;
pub mod math;
mod pose;
pub mod rng;
mod skeleton;

pub use animated::AnimatedModels;
pub use character_rig::CharacterRig;
pub use error::{Error, Result};
/// The math library Tassel's API speaks (glam 0.32), re-exported so a user needs no
/// second, possibly different, version.
pub use glam;
pub use instance::{CharacterSim, EVENT_PREFIX};
pub use math::Transform;
pub use pose::{CrowdPose, LocalToModelJob, ModelToLocalJob, Pose};
pub use skeleton::{Skeleton, SkeletonBuilder, MAX_JOINTS, NO_PARENT};
