//! Reading glTF / GLB into a skeleton, skins and clips.

use crate::accessor;
use crate::error::GltfError;
use glam::{Mat4, Quat, Vec3};
use gltf::accessor::DataType::{self, F32, I16, I8, U16, U8};
use gltf::accessor::Dimensions::{self, Mat4 as Mat4D, Scalar, Vec3 as Vec3D, Vec4 as Vec4D};
use gltf::animation::Property;
use std::path::Path;
use tassel::anim::{Channel, Clip, Interpolation, JointTrack};
use tassel::{Skeleton, SkeletonBuilder, Transform};

/// One skin of the file.
#[derive(Debug, Clone)]
pub struct SkinInfo {
    /// The skin's name.
    pub name: String,
    /// Its joints, as skeleton indices.
    pub joints: Vec<usize>,
    /// One inverse bind matrix per joint (identity when the file gives none).
    pub inverse_bind: Vec<Mat4>,
}

/// A loaded glTF file: every node is a joint of `skeleton`.
#[derive(Debug, Clone)]
pub struct Model {
    /// All nodes, depth-first.
    pub skeleton: Skeleton,
    /// glTF node index → skeleton joint.
    pub node_to_joint: Vec<usize>,
    /// Skeleton joint → glTF node index.
    pub joint_to_node: Vec<usize>,
    /// The file's skins.
    pub skins: Vec<SkinInfo>,
    /// The file's animations as clips over skeleton joints.
    pub clips: Vec<Clip>,
    /// Things the loader accepted but a user should know.
    pub warnings: Vec<String>,
    /// The file's VRM spring bones (`VRMC_springBone` 1.0 or VRM 0.x), if any.
    pub vrm: Option<crate::VrmInfo>,
    /// Every triangle-list mesh primitive, placed at rest (e.g. for a controller level).
    pub meshes: Vec<crate::MeshInstance>,
    /// The parsed JSON and resolved buffers, for export.
    pub source: crate::ExportSource,
}

impl Model {
    /// The animation called `name`, if the file has one.
    pub fn clip(&self, name: &str) -> Option<&Clip> {
        self.clips.iter().find(|c| c.name == name)
    }

    /// The index of the joint of the node called `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.skeleton.find(name)
    }
}

/// Loads a `.gltf`, `.glb` or `.vrm` file.
///
/// A file larger than [`MAX_FILE_BYTES`] is refused before it is read.
pub fn load(path: &Path) -> Result<Model, GltfError> {
    let io = |source| GltfError::Io {
        path: path.display().to_string(),
        source,
    };
    let bytes = crate::uri::read_at_most(path, MAX_FILE_BYTES + 1).map_err(io)?;
    if bytes.len() > MAX_FILE_BYTES {
        return Err(GltfError::Invalid {
            path: path.display().to_string(),
            message: format!("the file is larger than the limit of {MAX_FILE_BYTES} bytes"),
        });
    }
    load_slice(&bytes, path.parent(), &path.display().to_string())
}

/// The largest glTF/GLB file, and the most bytes all of one file's buffers may hold
/// together (512 MiB).
pub const MAX_FILE_BYTES: usize = 512 << 20;

/// Loads from bytes; `base_dir` resolves external buffers (`None`: the bytes are all
/// there is, and a buffer in an external file is an error naming its URI; data: URIs and
/// GLB chunks work either way); `name` is used in messages.
pub fn load_slice(bytes: &[u8], base_dir: Option<&Path>, name: &str) -> Result<Model, GltfError> {
    let invalid = |message: String| GltfError::Invalid {
        path: name.to_string(),
        message,
    };
    // The gltf crate subtracts the header size from the GLB length field unchecked (found
    // by fuzzing: an overflow panic in debug builds).
    if let Some(length) = bytes.get(8..12).filter(|_| bytes.starts_with(b"glTF")) {
        let length = u32::from_le_bytes([length[0], length[1], length[2], length[3]]);
        if length < 12 {
            return Err(invalid(format!(
                "the GLB header gives a length of {length} bytes, less than the header itself"
            )));
        }
    }
    let gltf =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| invalid(e.to_string()))?;
    validate(&gltf).map_err(invalid)?;
    let doc = &gltf.document;
    let mut buffers: Vec<Vec<u8>> = Vec::new();
    let mut total = 0usize;
    for b in doc.buffers() {
        total = total.saturating_add(b.length());
        if total > MAX_FILE_BYTES {
            return Err(invalid(format!(
                "buffer {} takes the file's buffers past the limit of {MAX_FILE_BYTES} bytes",
                b.index()
            )));
        }
        let data = match b.source() {
            gltf::buffer::Source::Bin => gltf
                .blob
                .clone()
                .ok_or_else(|| invalid("GLB has no BIN chunk".into()))?,
            gltf::buffer::Source::Uri(uri) => {
                crate::uri::read_uri(uri, base_dir, b.length()).map_err(invalid)?
            }
        };
        if data.len() < b.length() {
            return Err(invalid(format!(
                "buffer {} holds {} bytes, {} declared",
                b.index(),
                data.len(),
                b.length()
            )));
        }
        buffers.push(data);
    }
    // Accessor reads must stay inside the buffers: check views first so the reader never
    // sees an out-of-range view.
    for v in doc.views() {
        let end = v.offset().saturating_add(v.length());
        if end > buffers[v.buffer().index()].len() {
            return Err(invalid(format!(
                "bufferView {} runs past the end of its buffer",
                v.index()
            )));
        }
    }

    let mut warnings = Vec::new();
    let node_count = doc.nodes().len();
    if node_count == 0 {
        return Err(invalid("the file has no nodes".into()));
    }
    let mut parent_of: Vec<Option<usize>> = vec![None; node_count];
    for n in doc.nodes() {
        for c in n.children() {
            if let Some(p) = parent_of[c.index()] {
                return Err(invalid(format!(
                    "node {} has two parents ({p} and {})",
                    c.index(),
                    n.index()
                )));
            }
            parent_of[c.index()] = Some(n.index());
        }
    }
    let mut builder = SkeletonBuilder::new();
    let mut seen = std::collections::HashSet::new();
    for n in doc.nodes() {
        let base = n
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("node{}", n.index()));
        let name = if seen.contains(&base) {
            let renamed = format!("{base}#{}", n.index());
            warnings.push(format!(
                "node {} repeats the name '{base}'; called '{renamed}'",
                n.index()
            ));
            renamed
        } else {
            base
        };
        seen.insert(name.clone());
        let (t, r, s) = n.transform().decomposed();
        let rest = Transform::new(
            Vec3::from(t),
            Quat::from_array(r).normalize(),
            Vec3::from(s),
        );
        if !rest.is_finite() {
            return Err(invalid(format!(
                "node {} has a non-finite transform",
                n.index()
            )));
        }
        let sc = Vec3::from(s);
        if sc.min_element() < 0.01 || sc.max_element() > 100.0 {
            warnings.push(format!("node '{name}' has an unusual scale {sc}"));
        }
        builder.add(name, parent_of[n.index()], rest);
    }
    let (skeleton, node_to_joint) = builder.build().map_err(|source| GltfError::Skeleton {
        path: name.to_string(),
        source,
    })?;
    let mut joint_to_node = vec![0; node_count];
    for (node, &j) in node_to_joint.iter().enumerate() {
        joint_to_node[j] = node;
    }

    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|v| v.as_slice());
    let buffer_len = |i: usize| buffers.get(i).map_or(0, Vec::len);
    let mut skins = Vec::new();
    let mut in_skin = vec![false; skeleton.len()];
    for skin in doc.skins() {
        let joints: Vec<usize> = skin.joints().map(|j| node_to_joint[j.index()]).collect();
        if let Some(acc) = skin.inverse_bind_matrices() {
            let what = format!("skin {} inverse bind matrices", skin.index());
            accessor::check(&acc, &[(F32, Mat4D)], &buffer_len, &what).map_err(invalid)?;
        }
        let inverse_bind: Vec<Mat4> = match skin.reader(get).read_inverse_bind_matrices() {
            Some(it) => it.map(|m| Mat4::from_cols_array_2d(&m)).collect(),
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        if inverse_bind.len() < joints.len() {
            return Err(invalid(format!(
                "skin {} has fewer inverse bind matrices than joints",
                skin.index()
            )));
        }
        // A skin normally hangs from one root; joints whose parent is outside the skin
        // beyond the first are worth a look (they move with nodes the skin does not list).
        // (A set, not `joints.contains`: a skin may list thousands of joints.)
        for &j in &joints {
            if std::mem::replace(&mut in_skin[j], true) {
                return Err(invalid(format!(
                    "skin {} lists joint '{}' twice (skin joints must be unique)",
                    skin.index(),
                    skeleton.name(j)
                )));
            }
        }
        let roots: Vec<usize> = joints
            .iter()
            .copied()
            .filter(|&j| skeleton.parent(j).is_none_or(|p| !in_skin[p]))
            .collect();
        for &j in &joints {
            in_skin[j] = false;
        }
        // The first few by name, then how many (a broken skin may have thousands).
        for &j in roots.iter().skip(1).take(8) {
            warnings.push(format!(
                "skin {} ('{}'): joint '{}' has no parent in the skin ({} such joints)",
                skin.index(),
                skin.name().unwrap_or(""),
                skeleton.name(j),
                roots.len()
            ));
        }
        skins.push(SkinInfo {
            name: skin.name().unwrap_or("").to_string(),
            joints,
            inverse_bind,
        });
    }

    let mut clips = Vec::new();
    for anim in doc.animations() {
        let clip_name = anim
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("animation_{}", anim.index()));
        let mut tracks: Vec<JointTrack> = Vec::new();
        let mut duration = 0.0f32;
        for ch in anim.channels() {
            let joint = node_to_joint[ch.target().node().index()];
            let interpolation = match ch.sampler().interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let what = format!(
                "animation '{clip_name}' node {}",
                ch.target().node().index()
            );
            let sampler = ch.sampler();
            accessor::check(
                &sampler.input(),
                &[(F32, Scalar)],
                &buffer_len,
                &format!("{what} key times"),
            )
            .map_err(invalid)?;
            let normalized = [F32, I8, U8, I16, U16];
            let outputs: Vec<(DataType, Dimensions)> = match ch.target().property() {
                Property::Translation | Property::Scale => vec![(F32, Vec3D)],
                Property::Rotation => normalized.iter().map(|&t| (t, Vec4D)).collect(),
                Property::MorphTargetWeights => normalized.iter().map(|&t| (t, Scalar)).collect(),
            };
            accessor::check(
                &sampler.output(),
                &outputs,
                &buffer_len,
                &format!("{what} key values"),
            )
            .map_err(invalid)?;
            let reader = ch.reader(get);
            let times: Vec<f32> = reader
                .read_inputs()
                .ok_or_else(|| invalid(format!("animation '{clip_name}': unreadable key times")))?
                .collect();
            duration = duration.max(times.last().copied().unwrap_or(0.0));
            let idx = match tracks.iter().position(|t| t.joint == joint) {
                Some(i) => i,
                None => {
                    tracks.push(JointTrack {
                        joint,
                        translation: None,
                        rotation: None,
                        scale: None,
                    });
                    tracks.len() - 1
                }
            };
            let track = &mut tracks[idx];
            use gltf::animation::util::ReadOutputs;
            match reader.read_outputs() {
                Some(ReadOutputs::Translations(it)) => {
                    let c = Channel {
                        interpolation,
                        times,
                        values: it.map(Vec3::from).collect(),
                    };
                    c.validate(&what).map_err(|e| invalid(e.to_string()))?;
                    track.translation = Some(c);
                }
                Some(ReadOutputs::Rotations(it)) => {
                    let c = Channel {
                        interpolation,
                        times,
                        values: it.into_f32().map(Quat::from_array).collect(),
                    };
                    c.validate(&what).map_err(|e| invalid(e.to_string()))?;
                    track.rotation = Some(c);
                }
                Some(ReadOutputs::Scales(it)) => {
                    let c = Channel {
                        interpolation,
                        times,
                        values: it.map(Vec3::from).collect(),
                    };
                    c.validate(&what).map_err(|e| invalid(e.to_string()))?;
                    track.scale = Some(c);
                }
                Some(ReadOutputs::MorphTargetWeights(_)) => {
                    warnings.push(format!("{what}: morph target weights are not imported"));
                }
                None => return Err(invalid(format!("{what}: unreadable key values"))),
            }
        }
        clips.push(Clip {
            name: clip_name,
            duration,
            tracks,
        });
    }
    for ext in doc.extensions_used() {
        if !ext.starts_with("KHR_") && !ext.starts_with("VRMC_") && ext != "VRM" {
            warnings.push(format!(
                "extension '{ext}' is carried over but not interpreted"
            ));
        }
    }
    let json: serde_json::Value =
        serde_json::to_value(doc.as_json()).map_err(|e| invalid(e.to_string()))?;
    let json = raw_json(bytes).unwrap_or(json);
    let vrm = crate::vrm::read(&json, &node_to_joint, &mut warnings)
        .map_err(|m| invalid(format!("spring bones: {m}")))?;
    if let Some(v) = &vrm {
        v.springs
            .validate_for(&skeleton)
            .map_err(|e| invalid(format!("spring bones: {e}")))?;
    }
    let meshes = crate::mesh::read_meshes(
        doc,
        &buffers,
        &buffer_len,
        &skeleton,
        &node_to_joint,
        &mut warnings,
        &invalid,
    )?;
    Ok(Model {
        meshes,
        skeleton,
        node_to_joint,
        joint_to_node,
        skins,
        clips,
        warnings,
        vrm,
        source: crate::ExportSource {
            json,
            buffers,
            base_dir: base_dir.map(Path::to_path_buf),
        },
    })
}

/// Extensions a file may require that Tassel reads itself (the gltf crate does not know
/// them): the VRM family.
fn handled_here(ext: &str) -> bool {
    ext.starts_with("VRMC_") || ext == "VRM"
}

/// The gltf crate's validation, except that required VRM extensions are accepted.
fn validate(gltf: &gltf::Gltf) -> Result<(), String> {
    use gltf::json::validation::{Error as V, Validate};
    let root = gltf.document.as_json();
    // gltf-json 1.4's own validation indexes `accessors` with a primitive's POSITION
    // before checking it (found by fuzzing: an index past the end panicked there).
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let semantic = match semantic {
                        gltf::json::validation::Checked::Valid(s) => format!("{s:?}"),
                        gltf::json::validation::Checked::Invalid => "?".into(),
                    };
                    return Err(format!(
                        "invalid glTF: meshes[{m}].primitives[{p}].attributes[{semantic}]: \
                         accessor {} does not exist ({} accessors)",
                        index.value(),
                        root.accessors.len()
                    ));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        errors.push((path(), error))
    });
    errors.retain(|(path, error)| {
        let required = root.extensions_required.iter().enumerate().any(|(i, ext)| {
            handled_here(ext)
                && path
                    .as_str()
                    .starts_with(&format!("extensionsRequired[{i}]"))
        });
        !(required && *error == V::Unsupported)
    });
    // gltf-json 1.4 does not validate animation channel targets, and the gltf crate
    // unwraps them (found by fuzzing: a path of "tr0anslation" panicked).
    for (a, anim) in root.animations.iter().enumerate() {
        for (c, ch) in anim.channels.iter().enumerate() {
            let at = || {
                gltf::json::Path::new()
                    .field("animations")
                    .index(a)
                    .field("channels")
                    .index(c)
            };
            if ch.target.node.value() >= root.nodes.len() {
                errors.push((at().field("target").field("node"), V::IndexOutOfBounds));
            }
            if ch.target.path == gltf::json::validation::Checked::Invalid {
                errors.push((at().field("target").field("path"), V::Invalid));
            }
        }
    }
    match errors.first() {
        None => Ok(()),
        Some(_) => Err(format!(
            "invalid glTF: {}",
            errors
                .iter()
                .map(|(p, e)| format!("{}: {e:?}", p.as_str()))
                .collect::<Vec<_>>()
                .join("; ")
        )),
    }
}

/// The document's JSON exactly as written (keeps extensions the typed model drops).
fn raw_json(bytes: &[u8]) -> Option<serde_json::Value> {
    if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
        serde_json::from_slice(bytes.get(20..20 + len)?).ok()
    } else {
        serde_json::from_slice(bytes).ok()
    }
}
