//! glTF 2.0 import and export for Tassel.
//!
//! - [`load`] / [`load_slice`]: nodes (every node becomes a joint), skins with their
//!   inverse bind matrices, the rest pose and animation clips, and VRM spring bones
//!   (`VRMC_springBone` 1.0 with extended colliders and the `VRMC_springBone_limit` draft,
//!   VRM 0.x `secondaryAnimation`).
//! - [`export_glb`]: a GLB with the skeleton (and, when there was an input file, its
//!   meshes, skins, materials and textures) plus baked animations, one key per frame;
//!   baked keys can go into an input animation in place ([`BakedClip::merge_into`]);
//!   a document built from a skeleton can get a controller level as meshes
//!   ([`ExportSource::add_level`]) and a skinned body of tubes and sheets
//!   ([`ExportSource::add_body`]); a document can be made a VRM 1.0 avatar
//!   ([`ExportSource::add_vrm`]), and the built-in character is one ([`builtin_avatar`]).
//! - [`bake_clip`]: play a clip through a [`tassel::CharacterSim`] and key the bones it
//!   simulates.
//!
//! A skeleton written as a GLB and read back (a file works the same: [`load`] takes its
//! path):
//!
//! ```
//! use tassel_gltf::{export_glb, load_slice, BoneMesh, ExportSource};
//!
//! let character = tassel::builtin::character();
//! let source = ExportSource::from_skeleton(&character.skeleton, BoneMesh::None);
//! let glb = export_glb(&source, &[])?;
//! let model = load_slice(&glb, None, "character.glb")?;
//! assert_eq!(model.skeleton.len(), character.skeleton.len());
//! let head = model.skeleton.find("head").expect("the built-in character has a head");
//! assert_eq!(model.skeleton.name(head), "head");
//! # Ok::<(), tassel_gltf::GltfError>(())
//! ```

/// The core crate, re-exported (and with it `tassel::glam`).
pub use tassel;

mod accessor;
mod avatar;
mod bake;
mod builtin_look;
mod error;
mod export;
mod import;
mod mesh;
mod scene;
mod tessellate;
mod uri;
mod vrm;
mod vrm_export;
mod vrm_limit;

pub use avatar::builtin_avatar;
pub use bake::{
    bake_clip, key_times, play, BakeOptions, BakeSource, PlayedFrame, Sway, MAX_BAKE_KEYS,
};
pub use builtin_look::{builtin_body, group_color};
pub use error::{GltfError, PlayError};
pub use export::{export_glb, BakedClip, BakedTrack, BoneMesh, ExportSource};
pub use import::{load, load_slice, Model, SkinInfo, MAX_FILE_BYTES};
pub use mesh::MeshInstance;
pub use scene::{Body, LevelPart, Limb, Material, Sheet};
pub use vrm::{read_spring_bones, VrmInfo, VrmVersion, VRM0_TAIL_LENGTH};
pub use vrm_export::{VrmAvatar, VRM1_REQUIRED_BONES};
