//! The two assets the plugin loads: a character model (a glTF/GLB/VRM file's skeleton and
//! VRM spring bones) and a rig file (`.rig.toml`: chains, springs, cloths, ropes).

use bevy::asset::io::Reader;
use bevy::asset::{Asset, AssetLoader, AssetPath, LoadContext};
use bevy::reflect::TypePath;
use std::sync::Arc;
use tassel::dynamics::vrm::VrmSpringBones;
use tassel::dynamics::RigSettings;
use tassel::Skeleton;
use thiserror::Error;

/// A character model: its skeleton (every glTF node is a joint) and the VRM spring bones
/// the file defines (`VRMC_springBone` 1.0 or VRM 0.x), read by Tassel's glTF importer.
///
/// Loaded from a `.gltf`, `.glb` or `.vrm` file by asking for this type:
/// `asset_server.load::<TasselModel>("avatar.vrm")` (the plugin registers its loader for
/// the type, not for the extensions, so Bevy's own glTF loader still serves scenes from
/// the same path). A skeleton built in code becomes one with [`TasselModel::new`].
#[derive(Asset, TypePath, Debug, Clone)]
pub struct TasselModel {
    skeleton: Arc<Skeleton>,
    vrm: Option<VrmSpringBones>,
    entity_names: Vec<String>,
    warnings: Vec<String>,
}

impl TasselModel {
    /// A model from a skeleton made in code, with optional VRM springs. Its bones are
    /// found by the skeleton's joint names.
    pub fn new(skeleton: Skeleton, vrm: Option<VrmSpringBones>) -> Self {
        let entity_names = skeleton.names().to_vec();
        Self {
            skeleton: Arc::new(skeleton),
            vrm,
            entity_names,
            warnings: Vec::new(),
        }
    }

    /// A model from a file loaded by `tassel_gltf` ([`tassel_gltf::load`] or
    /// [`tassel_gltf::load_slice`]). Bones are looked up by the names Bevy's glTF loader
    /// gives node entities: the node's name, or `GltfNode{index}` for a node without one.
    pub fn from_gltf(model: &tassel_gltf::Model) -> Self {
        let nodes = model.source.json["nodes"].as_array();
        let entity_names = model
            .joint_to_node
            .iter()
            .map(|&n| {
                nodes
                    .and_then(|a| a.get(n))
                    .and_then(|node| node["name"].as_str())
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("GltfNode{n}"))
            })
            .collect();
        Self {
            skeleton: Arc::new(model.skeleton.clone()),
            vrm: model.vrm.as_ref().map(|v| v.springs.clone()),
            entity_names,
            warnings: model.warnings.clone(),
        }
    }

    /// The skeleton.
    pub fn skeleton(&self) -> &Arc<Skeleton> {
        &self.skeleton
    }

    /// The file's VRM spring bones, if it has any.
    pub fn vrm(&self) -> Option<&VrmSpringBones> {
        self.vrm.as_ref()
    }

    /// The `Name` of the entity that stands for joint `joint` (Bevy's naming of glTF nodes).
    pub fn entity_name(&self, joint: usize) -> Option<&str> {
        self.entity_names.get(joint).map(String::as_str)
    }

    /// What the importer accepted but a user should know (repeated node names, ...).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }
}

/// A rig file (`*.rig.toml`, the format of `tassel simulate --rig`): chains, springs,
/// cloths, ropes and their colliders, by bone name.
#[derive(Asset, TypePath, Debug, Clone)]
pub struct TasselRig(pub RigSettings);

/// Why an asset did not load.
#[derive(Debug, Error)]
pub enum TasselAssetError {
    /// The bytes could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The asset path.
        path: String,
        /// The reader's error.
        source: std::io::Error,
    },
    /// The glTF file was refused by Tassel's importer.
    #[error(transparent)]
    Gltf(#[from] tassel_gltf::GltfError),
    /// The rig file is not UTF-8 or not a valid rig.
    #[error("{path}: {message}")]
    Rig {
        /// The asset path.
        path: String,
        /// What is wrong (the rig parser's message names the key).
        message: String,
    },
}

/// Every byte of an asset, or an error naming its path.
async fn read_all(reader: &mut dyn Reader, path: &str) -> Result<Vec<u8>, TasselAssetError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .await
        .map_err(|source| TasselAssetError::Io {
            path: path.to_string(),
            source,
        })?;
    Ok(bytes)
}

/// Loads [`TasselModel`] from `.gltf` (with its buffers embedded), `.glb` and `.vrm` files.
#[derive(Default, TypePath)]
pub struct TasselModelLoader;

impl AssetLoader for TasselModelLoader {
    type Asset = TasselModel;
    type Settings = ();
    type Error = TasselAssetError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<TasselModel, TasselAssetError> {
        let path = load_context.path().to_string();
        let mut bytes = read_all(reader, &path).await?;
        if !bytes.starts_with(b"glTF") {
            bytes = inline_buffers(bytes, load_context).await?;
        }
        // No base directory: an asset source is not a folder on disk, and every buffer is
        // in the bytes by now (GLB's BIN chunk, data: URIs).
        let model = tassel_gltf::load_slice(&bytes, None, &path)?;
        Ok(TasselModel::from_gltf(&model))
    }

    // Chosen by type (`load::<TasselModel>`), so that Bevy's glTF loader keeps `.glb`
    // and `.gltf` paths (and `#Scene0` labels).
    fn extensions(&self) -> &[&str] {
        &[]
    }
}

/// A `.gltf` JSON's external buffers read through the asset source (beside the file) and
/// put in as base64 data URIs, so the importer needs no file system.
async fn inline_buffers(
    bytes: Vec<u8>,
    load_context: &mut LoadContext<'_>,
) -> Result<Vec<u8>, TasselAssetError> {
    use base64::Engine;
    let path = load_context.path().to_string();
    let invalid = |message: String| {
        TasselAssetError::Gltf(tassel_gltf::GltfError::Invalid {
            path: path.clone(),
            message,
        })
    };
    let mut json: serde_json::Value =
        serde_json::from_slice(&bytes).map_err(|e| invalid(format!("bad JSON: {e}")))?;
    let Some(buffers) = json.get_mut("buffers").and_then(|b| b.as_array_mut()) else {
        return Ok(bytes);
    };
    let mut changed = false;
    for buffer in buffers {
        let Some(uri) = buffer.get("uri").and_then(|u| u.as_str()) else {
            continue;
        };
        if uri.starts_with("data:") {
            continue;
        }
        // The importer's rule: a relative path inside the file's folder.
        if uri.is_empty() || uri.contains(':') || uri.split(['/', '\\']).any(|c| c == "..") {
            return Err(invalid(format!(
                "buffer URI '{uri}' is not a relative path inside the file's folder"
            )));
        }
        let target = load_context
            .path()
            .resolve_embed(&AssetPath::from(uri.to_string()));
        let data = load_context
            .read_asset_bytes(target.clone())
            .await
            .map_err(|e| invalid(format!("buffer '{target}': {e}")))?;
        let encoded = base64::engine::general_purpose::STANDARD.encode(&data);
        buffer["uri"] =
            serde_json::Value::String(format!("data:application/octet-stream;base64,{encoded}"));
        changed = true;
    }
    if !changed {
        return Ok(bytes);
    }
    serde_json::to_vec(&json).map_err(|e| invalid(format!("JSON: {e}")))
}

/// Loads [`TasselRig`] from `*.rig.toml` files.
#[derive(Default, TypePath)]
pub struct TasselRigLoader;

impl AssetLoader for TasselRigLoader {
    type Asset = TasselRig;
    type Settings = ();
    type Error = TasselAssetError;

    async fn load(
        &self,
        reader: &mut dyn Reader,
        _settings: &(),
        load_context: &mut LoadContext<'_>,
    ) -> Result<TasselRig, TasselAssetError> {
        let path = load_context.path().to_string();
        let bytes = read_all(reader, &path).await?;
        let text = std::str::from_utf8(&bytes).map_err(|e| TasselAssetError::Rig {
            path: path.clone(),
            message: format!("not UTF-8: {e}"),
        })?;
        let rig = RigSettings::from_toml_str(text).map_err(|e| TasselAssetError::Rig {
            path,
            message: e.to_string(),
        })?;
        Ok(TasselRig(rig))
    }

    fn extensions(&self) -> &[&str] {
        &["rig.toml"]
    }
}
