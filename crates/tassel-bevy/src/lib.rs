//! # tassel-bevy
//!
//! [Tassel](tassel)'s secondary motion — VRM spring bones, KawaiiPhysics-style chains,
//! springs, bone cloth and ropes — on Bevy 0.19 scenes, frame-rate independent by default.
//!
//! Add [`TasselPlugin`], then put a [`SecondaryMotion`] on the entity that holds a spawned
//! glTF/VRM scene:
//!
//! ```no_run
//! use bevy::prelude::*;
//! use tassel_bevy::prelude::*;
//!
//! fn setup(mut commands: Commands, assets: Res<AssetServer>) {
//!     commands.spawn((
//!         // The scene, by Bevy's glTF loader (`.vrm` too, with the `gltf` feature).
//!         WorldAssetRoot(assets.load(GltfAssetLabel::Scene(0).from_asset("avatar.vrm"))),
//!         // Its VRM spring bones, read from the same file by Tassel.
//!         SecondaryMotion::new(assets.load("avatar.vrm")),
//!     ));
//! }
//! # let _ = setup;
//! ```
//!
//! A rig file adds chains, springs, cloths and ropes to any glTF:
//! `SecondaryMotion::new(assets.load("Fox.glb")).with_rig(assets.load("fox.rig.toml"))`.
//!
//! ## One frame
//! In `PostUpdate`, after Bevy's animation ([`AnimationSystems`]) and before transform
//! propagation ([`TransformSystems::Propagate`]), in [`TasselSystems`] order:
//! 1. [`TasselSystems::Bind`]: characters whose assets have loaded and whose bones are
//!    spawned get a [`TasselCharacter`] (or a [`TasselFailed`] and a [`TasselError`]).
//! 2. [`TasselSystems::Step`]: each character reads its bones' `Transform`s (this frame's
//!    animated pose), steps by `Time`'s delta (0 on its first frame, which places every
//!    solver on the pose), and writes the simulated bones' `Transform`s.
//!
//! Systems that move a character (or animate it) must run before
//! [`TasselSystems::Step`]; systems that read the simulated pose, after it.
//!
//! ## Features
//! - `gltf`: registers Bevy's glTF loader for `.vrm` files as well (a VRM is a GLB), so
//!   `WorldAssetRoot(assets.load("a.vrm#Scene0"))` works.
//! - `gizmos`: [`TasselGizmosPlugin`] draws colliders, chains and VRM springs.
//!
//! Bevy's glam is Tassel's glam (0.32): positions and rotations pass through unchanged.

mod assets;
mod bind;
mod character;
mod controller;
mod convert;
mod crowd;
mod crowd_bones;
#[cfg(feature = "gizmos")]
mod gizmos;
mod shared;
mod spawn;
mod step;
#[cfg(feature = "gltf")]
mod vrm_scene;

pub use assets::{TasselAssetError, TasselModel, TasselModelLoader, TasselRig, TasselRigLoader};
pub use character::{SecondaryMotion, TasselCharacter, TasselFailed};
pub use controller::{CharacterController, TasselCollider, TasselLevel};
#[cfg(feature = "gizmos")]
pub use gizmos::TasselGizmosPlugin;
pub use shared::{SharedCollisionSource, SharedCollisionTarget};
pub use spawn::spawn_skeleton;
pub use step::{READ_TIME, SOLVE_TIME, STEP_TIME, WRITE_TIME};
pub use tassel;
pub use tassel::dynamics::SimMode;
#[cfg(feature = "gltf")]
pub use vrm_scene::VrmSceneLoader;

use bevy::app::{AnimationSystems, App, Plugin, PostUpdate};
use bevy::asset::AssetApp;
use bevy::diagnostic::RegisterDiagnostic;
use bevy::ecs::prelude::*;
use bevy::transform::TransformSystems;

/// The types a user needs.
pub mod prelude {
    #[cfg(feature = "gizmos")]
    pub use crate::TasselGizmosPlugin;
    pub use crate::{
        CharacterController, SecondaryMotion, SharedCollisionSource, SharedCollisionTarget,
        SimMode, TasselCharacter, TasselCollider, TasselError, TasselFailed, TasselLevel,
        TasselModel, TasselPlugin, TasselRig, TasselSystems,
    };
}

/// The plugin's system sets, in `PostUpdate`, in this order, before
/// [`TransformSystems::Propagate`]; `Bind` and `Step` after [`AnimationSystems`].
#[derive(SystemSet, Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TasselSystems {
    /// The [`TasselLevel`] follows the [`TasselCollider`] entities (added, moved, removed).
    Level,
    /// Every [`CharacterController`] moves by its `desired` translation.
    Control,
    /// Characters whose model, rig and bones are ready start.
    Bind,
    /// Every character reads its animated bones, steps, and writes the simulated ones.
    Step,
}

/// A character could not start, or a frame was skipped: which entity, and why. Also
/// logged. A frame error is reported once until the message changes.
#[derive(Message, Debug, Clone, PartialEq, Eq)]
pub struct TasselError {
    /// The [`SecondaryMotion`] entity.
    pub entity: Entity,
    /// What went wrong (a missing bone, a rig that does not fit, a NaN in a bone...).
    pub message: String,
}

/// Secondary motion for Bevy: the [`TasselModel`] and [`TasselRig`] assets and loaders,
/// and the [`TasselSystems`] in `PostUpdate`. Needs Bevy's `AssetPlugin` (in
/// `DefaultPlugins`; add it to `MinimalPlugins` for a headless app).
#[derive(Default)]
pub struct TasselPlugin;

impl Plugin for TasselPlugin {
    fn build(&self, app: &mut App) {
        for d in step::step_time_diagnostics() {
            app.register_diagnostic(d);
        }
        app.init_asset::<TasselModel>()
            .init_asset::<TasselRig>()
            .register_asset_loader(TasselModelLoader)
            .register_asset_loader(TasselRigLoader)
            .add_message::<TasselError>()
            .init_resource::<bind::RigCache>()
            .init_resource::<crowd::Crowds>()
            .init_resource::<TasselLevel>()
            .configure_sets(
                PostUpdate,
                (
                    TasselSystems::Level,
                    TasselSystems::Control,
                    TasselSystems::Bind,
                    TasselSystems::Step,
                )
                    .chain()
                    .before(TransformSystems::Propagate),
            )
            .configure_sets(PostUpdate, TasselSystems::Bind.after(AnimationSystems))
            .add_systems(
                PostUpdate,
                (
                    controller::sync_level.in_set(TasselSystems::Level),
                    controller::move_characters.in_set(TasselSystems::Control),
                    bind::bind_characters.in_set(TasselSystems::Bind),
                    (shared::hand_over_shared_colliders, step::step_characters)
                        .chain()
                        .in_set(TasselSystems::Step),
                ),
            );
    }

    // In `cleanup`, after every plugin's `finish`: `GltfPlugin` makes its loader's
    // parts in `finish`, and may be added after this plugin.
    #[cfg(feature = "gltf")]
    fn cleanup(&self, app: &mut App) {
        vrm_scene::register(app);
    }
}

/// How many kinds of character (model, rig, mode) are compiled and alive: characters of
/// one kind share one compiled rig, freed with the last of them.
pub fn live_character_kinds(world: &World) -> usize {
    world
        .get_resource::<bind::RigCache>()
        .map_or(0, bind::RigCache::live)
}
