//! Writing GLB files: the input document (or a skeleton built from scratch) plus baked
//! animations.

use crate::error::GltfError;
use glam::{Quat, Vec3};
use serde_json::{json, Value};
use std::path::PathBuf;
use tassel::{Pose, Skeleton};

/// A document to write: its JSON and its buffers' bytes (index for index).
#[derive(Debug, Clone)]
pub struct ExportSource {
    /// The glTF JSON.
    pub json: Value,
    /// The bytes of each buffer in `json["buffers"]`.
    pub buffers: Vec<Vec<u8>>,
    /// Where relative image URIs are resolved (`None`: nowhere; an external image is an
    /// error naming its URI).
    pub base_dir: Option<PathBuf>,
}

/// Whether a document built from a skeleton gets a visible mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoneMesh {
    /// Nodes only.
    None,
    /// A skinned octahedral "bone" from every joint to each child, so that any viewer
    /// shows the skeleton move; links from a root joint at the origin (a root-motion bone
    /// under the feet) are left out.
    Octahedra,
}

/// Baked keys of one node; each present list has one value per clip time.
#[derive(Debug, Clone, Default)]
pub struct BakedTrack {
    /// The glTF node index.
    pub node: usize,
    /// Translations.
    pub translations: Option<Vec<Vec3>>,
    /// Rotations.
    pub rotations: Option<Vec<Quat>>,
    /// Scales.
    pub scales: Option<Vec<Vec3>>,
}

/// A baked clip: LINEAR keys at `times`.
#[derive(Debug, Clone, Default)]
pub struct BakedClip {
    /// Name; without `merge_into`, an input animation of the same name is replaced.
    pub name: String,
    /// Key times, strictly increasing, seconds.
    pub times: Vec<f32>,
    /// Tracks.
    pub tracks: Vec<BakedTrack>,
    /// `Some(a)`: the keys go into the input's animation `a` in place (its name and index
    /// kept): its channels on the nodes and properties these tracks key are replaced, every
    /// other channel is kept as it was. `None`: a whole animation, added at the end.
    pub merge_into: Option<usize>,
}

impl ExportSource {
    /// A document holding `skeleton` as nodes (node index = joint index), optionally with a
    /// skinned bone mesh.
    pub fn from_skeleton(skeleton: &Skeleton, mesh: BoneMesh) -> ExportSource {
        let mut nodes = Vec::new();
        for i in 0..skeleton.len() {
            let t = skeleton.rest()[i];
            let mut n = json!({
                "name": skeleton.name(i),
                "translation": t.translation.to_array(),
                "rotation": t.rotation.normalize().to_array(),
                "scale": t.scale.to_array(),
            });
            let kids: Vec<usize> = skeleton.children(i).collect();
            if !kids.is_empty() {
                n["children"] = json!(kids);
            }
            nodes.push(n);
        }
        let roots: Vec<usize> = (0..skeleton.len())
            .filter(|&i| skeleton.parent(i).is_none())
            .collect();
        let mut src = ExportSource {
            json: json!({
                "asset": { "version": "2.0", "generator": "tassel" },
                "scene": 0,
                "scenes": [ { "nodes": roots } ],
                "nodes": nodes,
            }),
            buffers: vec![Vec::new()],
            base_dir: None,
        };
        src.json["buffers"] = json!([{ "byteLength": 0 }]);
        if mesh == BoneMesh::Octahedra {
            add_bone_mesh(&mut src, skeleton);
        }
        src
    }
}

fn add_bone_mesh(src: &mut ExportSource, sk: &Skeleton) {
    let rest = Pose::rest(sk);
    let mut pos: Vec<f32> = Vec::new();
    let mut joints: Vec<u16> = Vec::new();
    let mut idx: Vec<u16> = Vec::new();
    for c in 0..sk.len() {
        let Some(p) = sk.parent(c) else { continue };
        if sk.parent(p).is_none() && rest.models[p].translation == Vec3::ZERO {
            continue;
        }
        let a = rest.models[p].translation;
        let b = rest.models[c].translation;
        let len = (b - a).length();
        if len < 1e-4 || pos.len() / 3 + 6 > u16::MAX as usize {
            continue;
        }
        let dir = (b - a) / len;
        let u = dir.any_orthonormal_vector();
        let v = dir.cross(u);
        let w = (0.12 * len).clamp(0.004, 0.03);
        let mid = a + dir * (0.2 * len);
        let base = (pos.len() / 3) as u16;
        for q in [a, mid + u * w, mid + v * w, mid - u * w, mid - v * w, b] {
            pos.extend(q.to_array());
            joints.extend([p as u16, 0, 0, 0]);
        }
        for k in 0..4u16 {
            let (s, t) = (1 + k, 1 + (k + 1) % 4);
            idx.extend([base, base + t, base + s, base + s, base + t, base + 5]);
        }
    }
    if idx.is_empty() {
        return;
    }
    let weights: Vec<f32> = (0..joints.len() / 4)
        .flat_map(|_| [1.0, 0.0, 0.0, 0.0])
        .collect();
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for p in pos.chunks(3) {
        let p = Vec3::new(p[0], p[1], p[2]);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let skin = skin_of(src, sk);
    let mut w = Writer::new(src);
    let a_pos = w.accessor(
        &f32_bytes(&pos),
        5126,
        "VEC3",
        pos.len() / 3,
        Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
        Some(34962),
    );
    let jb: Vec<u8> = joints.iter().flat_map(|j| j.to_le_bytes()).collect();
    let a_j = w.accessor(&jb, 5123, "VEC4", joints.len() / 4, None, Some(34962));
    let a_w = w.accessor(
        &f32_bytes(&weights),
        5126,
        "VEC4",
        weights.len() / 4,
        None,
        Some(34962),
    );
    let ib: Vec<u8> = idx.iter().flat_map(|j| j.to_le_bytes()).collect();
    let a_i = w.accessor(&ib, 5123, "SCALAR", idx.len(), None, Some(34963));
    let json = &mut src.json;
    let mesh = push_item(
        json,
        "meshes",
        json!({ "name": "bones", "primitives": [ {
            "attributes": { "POSITION": a_pos, "JOINTS_0": a_j, "WEIGHTS_0": a_w },
            "indices": a_i,
        } ] }),
    );
    let mesh_node = push_item(
        json,
        "nodes",
        json!({ "name": "bones", "mesh": mesh, "skin": skin }),
    );
    if let Some(a) = json["scenes"][0]["nodes"].as_array_mut() {
        a.push(json!(mesh_node));
    }
}

/// Appends `item` to the array `json[key]` (made if missing) and returns its index.
pub(crate) fn push_item(json: &mut Value, key: &str, item: Value) -> usize {
    let Some(obj) = json.as_object_mut() else {
        return 0;
    };
    let arr = obj.entry(key).or_insert(json!([]));
    if !arr.is_array() {
        *arr = json!([]);
    }
    let arr = arr.as_array_mut().expect("made an array above");
    arr.push(item);
    arr.len() - 1
}

/// The skin over every joint of `sk` (node index = joint index, bind pose = rest): the
/// document's skin named "skeleton" if there is one, else a new one.
pub(crate) fn skin_of(src: &mut ExportSource, sk: &Skeleton) -> usize {
    if let Some(i) = src
        .json
        .get("skins")
        .and_then(Value::as_array)
        .and_then(|s| s.iter().position(|k| k["name"] == "skeleton"))
    {
        return i;
    }
    let rest = Pose::rest(sk);
    let ibm: Vec<f32> = rest
        .models
        .iter()
        .flat_map(|m| m.to_mat4().inverse().to_cols_array())
        .collect();
    let a_ibm = Writer::new(src).accessor(&f32_bytes(&ibm), 5126, "MAT4", sk.len(), None, None);
    let root = (0..sk.len()).find(|&i| sk.parent(i).is_none()).unwrap_or(0);
    push_item(
        &mut src.json,
        "skins",
        json!({ "name": "skeleton", "joints": (0..sk.len()).collect::<Vec<_>>(), "inverseBindMatrices": a_ibm, "skeleton": root }),
    )
}

pub(crate) fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Appends data to buffer 0 of a source with one buffer.
pub(crate) struct Writer<'a> {
    src: &'a mut ExportSource,
}

impl<'a> Writer<'a> {
    pub(crate) fn new(src: &'a mut ExportSource) -> Self {
        Self { src }
    }

    pub(crate) fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        let bin = &mut self.src.buffers[0];
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        let views = self
            .src
            .json
            .as_object_mut()
            .unwrap()
            .entry("bufferViews")
            .or_insert(json!([]));
        let mut v = json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        let arr = views.as_array_mut().unwrap();
        arr.push(v);
        arr.len() - 1
    }

    pub(crate) fn accessor(
        &mut self,
        bytes: &[u8],
        component: u32,
        kind: &str,
        count: usize,
        min_max: Option<(Vec<f32>, Vec<f32>)>,
        target: Option<u32>,
    ) -> usize {
        let view = self.view(bytes, target);
        let mut a =
            json!({ "bufferView": view, "componentType": component, "count": count, "type": kind });
        if let Some((lo, hi)) = min_max {
            a["min"] = json!(lo);
            a["max"] = json!(hi);
        }
        let accessors = self
            .src
            .json
            .as_object_mut()
            .unwrap()
            .entry("accessors")
            .or_insert(json!([]));
        let arr = accessors.as_array_mut().unwrap();
        arr.push(a);
        arr.len() - 1
    }
}

/// Merges every buffer of `src` into one (GLB's BIN chunk) and embeds external images.
fn merge_buffers(src: &ExportSource) -> Result<ExportSource, GltfError> {
    let mut json = src.json.clone();
    let mut bin: Vec<u8> = Vec::new();
    let mut offsets = Vec::new();
    for b in &src.buffers {
        while !bin.len().is_multiple_of(8) {
            bin.push(0);
        }
        offsets.push(bin.len());
        bin.extend_from_slice(b);
    }
    if let Some(views) = json.get_mut("bufferViews").and_then(Value::as_array_mut) {
        for v in views {
            let b = v["buffer"].as_u64().unwrap_or(0) as usize;
            let off = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
            v["buffer"] = json!(0);
            v["byteOffset"] = json!(off + offsets.get(b).copied().unwrap_or(0));
        }
    }
    json["buffers"] = json!([{ "byteLength": 0 }]);
    let mut out = ExportSource {
        json,
        buffers: vec![bin],
        base_dir: src.base_dir.clone(),
    };
    let image_count = out
        .json
        .get("images")
        .and_then(Value::as_array)
        .map(|a| a.len())
        .unwrap_or(0);
    for i in 0..image_count {
        let uri = out.json["images"][i]
            .get("uri")
            .and_then(Value::as_str)
            .map(str::to_string);
        let Some(uri) = uri else { continue };
        if uri.starts_with("data:") {
            continue;
        }
        let bytes = crate::uri::read_uri(&uri, src.base_dir.as_deref(), crate::MAX_FILE_BYTES)
            .map_err(|message| GltfError::Invalid {
                path: format!("image {i}"),
                message,
            })?;
        let mime = if uri.to_ascii_lowercase().ends_with(".png") {
            "image/png"
        } else {
            "image/jpeg"
        };
        let view = Writer::new(&mut out).view(&bytes, None);
        let img = &mut out.json["images"][i];
        if let Some(o) = img.as_object_mut() {
            o.remove("uri");
        }
        img["bufferView"] = json!(view);
        img["mimeType"] = json!(mime);
    }
    Ok(out)
}

/// Writes `source` with `clips` added as animations (replacing input animations of the
/// same name) as GLB bytes.
pub fn export_glb(source: &ExportSource, clips: &[BakedClip]) -> Result<Vec<u8>, GltfError> {
    let mut out = merge_buffers(source)?;
    let invalid = |m: String| GltfError::Invalid {
        path: "<export>".into(),
        message: m,
    };
    let node_count = out
        .json
        .get("nodes")
        .and_then(Value::as_array)
        .map(|a| a.len())
        .unwrap_or(0);
    let anim_count = out
        .json
        .get("animations")
        .and_then(Value::as_array)
        .map(|a| a.len())
        .unwrap_or(0);
    for clip in clips {
        if let Some(a) = clip.merge_into {
            if a >= anim_count {
                return Err(invalid(format!(
                    "clip '{}' merges into animation {a}, which does not exist",
                    clip.name
                )));
            }
            if clips.iter().filter(|c| c.merge_into == Some(a)).count() > 1 {
                return Err(invalid(format!("two clips merge into animation {a}")));
            }
        }
    }
    // Merged animations lose the channels they re-key; whole clips replace input
    // animations of the same name (marked null here, removed at the end so that the
    // indices of the merged ones hold meanwhile).
    if let Some(anims) = out.json.get_mut("animations").and_then(Value::as_array_mut) {
        for (a, anim) in anims.iter_mut().enumerate() {
            if let Some(clip) = clips.iter().find(|c| c.merge_into == Some(a)) {
                drop_channels(anim, clip);
            } else if clips.iter().any(|c| {
                c.merge_into.is_none()
                    && anim.get("name").and_then(Value::as_str) == Some(c.name.as_str())
            }) {
                *anim = Value::Null;
            }
        }
    }
    for clip in clips {
        let n = clip.times.len();
        if n == 0
            || clip.times.windows(2).any(|w| w[1] <= w[0])
            || clip.times.iter().any(|t| !t.is_finite())
        {
            return Err(invalid(format!(
                "clip '{}': key times must be finite and increasing",
                clip.name
            )));
        }
        let mut w = Writer::new(&mut out);
        let input = w.accessor(
            &f32_bytes(&clip.times),
            5126,
            "SCALAR",
            n,
            Some((vec![clip.times[0]], vec![clip.times[n - 1]])),
            None,
        );
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for tr in &clip.tracks {
            if tr.node >= node_count {
                return Err(invalid(format!(
                    "clip '{}' names node {}, which does not exist",
                    clip.name, tr.node
                )));
            }
            let mut push = |path: &str,
                            data: Vec<f32>,
                            kind: &str,
                            count: usize|
             -> Result<(), GltfError> {
                if count != n || data.iter().any(|x| !x.is_finite()) {
                    return Err(invalid(format!(
                        "clip '{}' node {} {path}: {count} finite keys needed, one per time",
                        clip.name, tr.node
                    )));
                }
                let out_acc = w.accessor(&f32_bytes(&data), 5126, kind, count, None, None);
                samplers
                    .push(json!({ "input": input, "output": out_acc, "interpolation": "LINEAR" }));
                channels.push(json!({ "sampler": samplers.len() - 1, "target": { "node": tr.node, "path": path } }));
                Ok(())
            };
            if let Some(v) = &tr.translations {
                push(
                    "translation",
                    v.iter().flat_map(|x| x.to_array()).collect(),
                    "VEC3",
                    v.len(),
                )?;
            }
            if let Some(v) = &tr.rotations {
                // Keep neighbouring keys in one hemisphere so LINEAR playback takes the short way.
                let mut prev = Quat::IDENTITY;
                let mut data = Vec::with_capacity(v.len() * 4);
                for (i, q) in v.iter().enumerate() {
                    let mut q = q.normalize();
                    if i > 0 && q.dot(prev) < 0.0 {
                        q = -q;
                    }
                    prev = q;
                    data.extend(q.to_array());
                }
                push("rotation", data, "VEC4", v.len())?;
            }
            if let Some(v) = &tr.scales {
                push(
                    "scale",
                    v.iter().flat_map(|x| x.to_array()).collect(),
                    "VEC3",
                    v.len(),
                )?;
            }
        }
        let anims = out
            .json
            .as_object_mut()
            .unwrap()
            .entry("animations")
            .or_insert(json!([]));
        let anims = anims.as_array_mut().unwrap();
        match clip.merge_into {
            Some(p) => {
                let anim = &mut anims[p];
                let base = anim["samplers"].as_array().map(|s| s.len()).unwrap_or(0);
                for ch in &mut channels {
                    let k = ch["sampler"].as_u64().unwrap_or(0) as usize;
                    ch["sampler"] = json!(base + k);
                }
                append(anim, "samplers", samplers);
                append(anim, "channels", channels);
            }
            None => {
                anims.push(json!({ "name": clip.name, "samplers": samplers, "channels": channels }))
            }
        }
    }
    if let Some(anims) = out.json.get_mut("animations").and_then(Value::as_array_mut) {
        anims.retain(|a| !a.is_null());
    }
    if out
        .json
        .get("animations")
        .and_then(Value::as_array)
        .map(|a| a.is_empty())
        .unwrap_or(false)
    {
        out.json.as_object_mut().unwrap().remove("animations");
    }
    write_glb(out)
}

/// Removes from `anim` the channels on the nodes and properties `clip` keys, and the
/// samplers no other channel uses (the remaining channels are renumbered).
fn drop_channels(anim: &mut Value, clip: &BakedClip) {
    let keyed = |node: u64, path: &str| {
        clip.tracks.iter().any(|t| {
            t.node as u64 == node
                && match path {
                    "translation" => t.translations.is_some(),
                    "rotation" => t.rotations.is_some(),
                    "scale" => t.scales.is_some(),
                    _ => false,
                }
        })
    };
    let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) else {
        return;
    };
    channels.retain(|ch| {
        let node = ch["target"].get("node").and_then(Value::as_u64);
        let path = ch["target"]
            .get("path")
            .and_then(Value::as_str)
            .unwrap_or("");
        !matches!(node, Some(n) if keyed(n, path))
    });
    let used: Vec<u64> = channels
        .iter()
        .filter_map(|c| c.get("sampler").and_then(Value::as_u64))
        .collect();
    let Some(samplers) = anim.get_mut("samplers").and_then(Value::as_array_mut) else {
        return;
    };
    let mut new_index = vec![None; samplers.len()];
    let mut kept = Vec::new();
    for (i, s) in samplers.drain(..).enumerate() {
        if used.contains(&(i as u64)) {
            new_index[i] = Some(kept.len());
            kept.push(s);
        }
    }
    *samplers = kept;
    if let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) {
        for ch in channels {
            let old = ch["sampler"].as_u64().unwrap_or(0) as usize;
            if let Some(Some(n)) = new_index.get(old) {
                ch["sampler"] = json!(n);
            }
        }
    }
}

fn append(obj: &mut Value, key: &str, items: Vec<Value>) {
    match obj.get_mut(key).and_then(Value::as_array_mut) {
        Some(a) => a.extend(items),
        None => obj[key] = Value::Array(items),
    }
}

fn write_glb(mut doc: ExportSource) -> Result<Vec<u8>, GltfError> {
    let mut bin = std::mem::take(&mut doc.buffers[0]);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    if bin.is_empty() {
        doc.json.as_object_mut().unwrap().remove("buffers");
    } else {
        doc.json["buffers"] = json!([{ "byteLength": bin.len() }]);
    }
    let mut text = serde_json::to_vec(&doc.json).map_err(|e| GltfError::Invalid {
        path: "<export>".into(),
        message: e.to_string(),
    })?;
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((text.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&text);
    if !bin.is_empty() {
        out.extend((bin.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(&bin);
    }
    Ok(out)
}
