//! Meshes for a document built from a skeleton (what `tassel demo` writes): a controller
//! level as shaded meshes, one node per collider placed like it, and a body of tubes and
//! sheets skinned to the skeleton with smooth weights at the joints.

use crate::error::GltfError;
use crate::export::{f32_bytes, push_item, skin_of, ExportSource, Writer};
use crate::tessellate::Geometry;
use glam::Vec3;
use serde_json::{json, Value};
use tassel::controller::LevelCollider;
use tassel::{Pose, Skeleton};

/// A plain material: one colour, not metallic, fairly rough.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// Name in the file.
    pub name: String,
    /// Base colour, linear RGBA in `[0, 1]`.
    pub color: [f32; 4],
    /// Both faces drawn (for sheets such as a skirt).
    pub double_sided: bool,
}

impl Material {
    /// An opaque, one-sided material of colour `rgb` (sRGB bytes, as a picker gives them).
    pub fn srgb(name: impl Into<String>, rgb: [u8; 3]) -> Self {
        let lin = |c: u8| {
            let c = c as f32 / 255.0;
            if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            }
        };
        Self {
            name: name.into(),
            color: [lin(rgb[0]), lin(rgb[1]), lin(rgb[2]), 1.0],
            double_sided: false,
        }
    }
}

/// A part of a skinned body: a tube from joint `joint`'s rest position to `tip` (rest,
/// model space), rounded at both ends, moving with `joint`. Where the tube meets the
/// tube of the joint above or of a child joint at its tip, the vertices near the joint
/// are shared half and half between the two, so that the skin bends smoothly.
#[derive(Debug, Clone, PartialEq)]
pub struct Limb {
    /// The joint that carries it.
    pub joint: usize,
    /// Where it ends, model space at rest (usually a child joint's rest position).
    pub tip: Vec3,
    /// Radius at the joint and at the tip, metres (> 0).
    pub radius: [f32; 2],
    /// Index into [`Body::materials`].
    pub material: usize,
}

/// A surface through joints (e.g. a skirt through its chains): `columns[i][k]` is a
/// vertex at rest position `.1` (model space) moving rigidly with joint `.0`; neighbouring
/// columns are joined by quads (the last to the first when `closed`).
#[derive(Debug, Clone, PartialEq)]
pub struct Sheet {
    /// Columns of vertices, all of the same length (≥ 2), at least two columns.
    pub columns: Vec<Vec<(usize, Vec3)>>,
    /// Join the last column to the first.
    pub closed: bool,
    /// Index into [`Body::materials`].
    pub material: usize,
}

/// A skinned body: limbs and sheets, one glTF primitive per material.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Body {
    /// Materials, referenced by index.
    pub materials: Vec<Material>,
    /// Tubes.
    pub limbs: Vec<Limb>,
    /// Surfaces.
    pub sheets: Vec<Sheet>,
}

/// One level collider to draw and its material (index into the `materials` given with it).
#[derive(Debug, Clone, Copy)]
pub struct LevelPart<'a> {
    /// The collider, at the pose the node gets.
    pub collider: &'a LevelCollider,
    /// Index into the materials list.
    pub material: usize,
}

fn invalid(message: String) -> GltfError {
    GltfError::Invalid {
        path: "<export>".into(),
        message,
    }
}

/// One vertex's skin: up to two joints with weights summing to 1.
type Skin = ([u16; 4], [f32; 4]);

fn skin(pairs: &[(usize, f32)]) -> Skin {
    let (mut j, mut w) = ([0u16; 4], [0f32; 4]);
    let mut k = 0;
    for &(joint, weight) in pairs {
        if weight <= 0.0 {
            continue;
        }
        j[k] = joint as u16;
        w[k] = weight;
        k += 1;
    }
    // Exactly 1 in f32: the last weight takes the rounding.
    if k > 1 {
        w[k - 1] = 1.0 - w[..k - 1].iter().sum::<f32>();
    }
    (j, w)
}

impl ExportSource {
    /// Adds the level as meshes: one node per part, placed at its collider's position and
    /// rotation, with the collider's shape in the node's frame (boxes, wedges and triangle
    /// meshes exactly, spheres and capsules as 12-sided meshes that reach their true
    /// extent along the collider's axes). Returns the node index of each part, in order
    /// (to animate a moving collider). Errors, before anything is written, for a material
    /// index out of range, a non-finite placement or a part without triangles.
    pub fn add_level(
        &mut self,
        parts: &[LevelPart<'_>],
        materials: &[Material],
    ) -> Result<Vec<usize>, GltfError> {
        if let Some(p) = parts.iter().find(|p| p.material >= materials.len()) {
            return Err(invalid(format!(
                "level part '{}': material {} of {}",
                p.collider.name,
                p.material,
                materials.len()
            )));
        }
        // Every shape is made before anything is written: an error leaves `self` as it was.
        let mut shapes = Vec::with_capacity(parts.len());
        for part in parts {
            let c = part.collider;
            if !(c.position.is_finite() && c.rotation.is_finite() && c.rotation.length() > 1e-6) {
                return Err(invalid(format!(
                    "level part '{}': position {} / rotation {} must be finite (rotation non-zero)",
                    c.name, c.position, c.rotation
                )));
            }
            let mut g = Geometry::default();
            g.level_shape(&part.collider.shape);
            if g.triangles.is_empty() {
                return Err(invalid(format!(
                    "level part '{}' has no triangles",
                    part.collider.name
                )));
            }
            shapes.push(g);
        }
        let first_material = self.add_materials(materials);
        let mut nodes = Vec::with_capacity(parts.len());
        for (part, g) in parts.iter().zip(shapes) {
            let c = part.collider;
            let prim = write_primitive(self, &g, None, first_material + part.material);
            let mesh = push_item(
                &mut self.json,
                "meshes",
                json!({ "name": c.name, "primitives": [prim] }),
            );
            let node = push_item(
                &mut self.json,
                "nodes",
                json!({
                    "name": c.name,
                    "mesh": mesh,
                    "translation": c.position.to_array(),
                    "rotation": c.rotation.normalize().to_array(),
                }),
            );
            add_to_scene(&mut self.json, node);
            nodes.push(node);
        }
        Ok(nodes)
    }

    /// Adds `body` as one skinned mesh over `skeleton`'s joints (node index = joint index,
    /// as [`ExportSource::from_skeleton`] builds them) and returns the mesh node's index.
    /// Errors (checked before anything is written) name the limb or sheet with a joint
    /// or material out of range, a radius that is not positive, or columns of different
    /// lengths, or say that the body is empty.
    pub fn add_body(&mut self, skeleton: &Skeleton, body: &Body) -> Result<usize, GltfError> {
        let n = skeleton.len();
        if n > u16::MAX as usize {
            return Err(invalid(format!("{n} joints; a skin holds at most 65 535")));
        }
        let nm = body.materials.len();
        for (i, l) in body.limbs.iter().enumerate() {
            if l.joint >= n || l.material >= nm {
                return Err(invalid(format!(
                    "limb {i}: joint {} of {n}, material {} of {nm}",
                    l.joint, l.material
                )));
            }
            if !(l.radius.iter().all(|r| r.is_finite() && *r > 0.0) && l.tip.is_finite()) {
                return Err(invalid(format!(
                    "limb {i} ({}): radii {:?} must be > 0 and the tip finite",
                    skeleton.name(l.joint),
                    l.radius
                )));
            }
        }
        for (i, s) in body.sheets.iter().enumerate() {
            let rows = s.columns.first().map_or(0, Vec::len);
            if s.material >= nm
                || s.columns.len() < 2
                || rows < 2
                || s.columns.iter().any(|c| c.len() != rows)
                || s.columns
                    .iter()
                    .flatten()
                    .any(|(j, p)| *j >= n || !p.is_finite())
            {
                return Err(invalid(format!(
                    "sheet {i}: needs at least 2 columns of one length ≥ 2, joints below {n}, \
                     finite positions and a material below {nm}"
                )));
            }
        }
        if body.limbs.is_empty() && body.sheets.is_empty() {
            return Err(invalid("the body has no limbs and no sheets".into()));
        }
        let rest = Pose::rest(skeleton);
        let at = |j: usize| rest.models[j].translation;
        let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-4;
        let first_material = self.add_materials(&body.materials);
        let mut prims = Vec::new();
        for m in 0..nm {
            let mut g = Geometry::default();
            let mut skins: Vec<Skin> = Vec::new();
            for l in body.limbs.iter().filter(|l| l.material == m) {
                // The limb above, ending where this one starts, and the child's limb
                // starting at this one's tip, share the vertices near the joint.
                let above = skeleton.parent(l.joint).filter(|&p| {
                    body.limbs
                        .iter()
                        .any(|o| o.joint == p && near(o.tip, at(l.joint)))
                });
                let below = body.limbs.iter().find_map(|o| {
                    (skeleton.parent(o.joint) == Some(l.joint) && near(at(o.joint), l.tip))
                        .then_some(o.joint)
                });
                let before = g.positions.len();
                g.capsule(at(l.joint), l.tip, l.radius[0], l.radius[1]);
                for &t in &g.tags[before..] {
                    let up = above.map_or(0.0, |_| 0.5 * (1.0 - t / 0.25).clamp(0.0, 1.0));
                    let down = below.map_or(0.0, |_| 0.5 * ((t - 0.75) / 0.25).clamp(0.0, 1.0));
                    skins.push(skin(&[
                        (l.joint, 1.0 - up - down),
                        (above.unwrap_or(0), up),
                        (below.unwrap_or(0), down),
                    ]));
                }
            }
            for s in body.sheets.iter().filter(|s| s.material == m) {
                sheet(&mut g, &mut skins, s);
            }
            if !g.triangles.is_empty() {
                prims.push(write_primitive(self, &g, Some(&skins), first_material + m));
            }
        }
        let skin = skin_of(self, skeleton);
        let mesh = push_item(
            &mut self.json,
            "meshes",
            json!({ "name": "body", "primitives": prims }),
        );
        let node = push_item(
            &mut self.json,
            "nodes",
            json!({ "name": "body", "mesh": mesh, "skin": skin }),
        );
        add_to_scene(&mut self.json, node);
        Ok(node)
    }

    fn add_materials(&mut self, materials: &[Material]) -> usize {
        let first = self
            .json
            .get("materials")
            .and_then(Value::as_array)
            .map_or(0, Vec::len);
        for m in materials {
            push_item(
                &mut self.json,
                "materials",
                json!({
                    "name": m.name,
                    "pbrMetallicRoughness": {
                        "baseColorFactor": m.color,
                        "metallicFactor": 0.0,
                        "roughnessFactor": 0.8,
                    },
                    "doubleSided": m.double_sided,
                }),
            );
        }
        first
    }
}

/// The sheet's quads, each vertex rigid to its joint; normals from the neighbouring
/// vertices (the material is expected to be double-sided).
fn sheet(g: &mut Geometry, skins: &mut Vec<Skin>, s: &Sheet) {
    let cols = s.columns.len();
    let rows = s.columns[0].len();
    let first = g.positions.len() as u32;
    let pos = |i: usize, k: usize| s.columns[i % cols][k].1;
    for i in 0..cols {
        for k in 0..rows {
            let down = pos(i, (k + 1).min(rows - 1)) - pos(i, k.saturating_sub(1));
            let (l, r) = if s.closed {
                (pos(i + cols - 1, k), pos(i + 1, k))
            } else {
                (pos(i.saturating_sub(1), k), pos((i + 1).min(cols - 1), k))
            };
            g.vertex(pos(i, k), (r - l).cross(down), 0.0);
            skins.push(skin(&[(s.columns[i][k].0, 1.0)]));
        }
    }
    let spans = if s.closed { cols } else { cols - 1 };
    let v = |i: usize, k: usize| first + ((i % cols) * rows + k) as u32;
    for i in 0..spans {
        for k in 0..rows - 1 {
            g.triangle(v(i, k), v(i + 1, k), v(i + 1, k + 1));
            g.triangle(v(i, k), v(i + 1, k + 1), v(i, k + 1));
        }
    }
}

/// Writes `g` (and its skin) as accessors and returns the primitive's JSON.
fn write_primitive(
    src: &mut ExportSource,
    g: &Geometry,
    skins: Option<&[Skin]>,
    material: usize,
) -> Value {
    let (lo, hi) = g.bounds();
    let flat = |v: &[Vec3]| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
    let mut w = Writer::new(src);
    let count = g.positions.len();
    let a_pos = w.accessor(
        &f32_bytes(&flat(&g.positions)),
        5126,
        "VEC3",
        count,
        Some((lo.to_array().to_vec(), hi.to_array().to_vec())),
        Some(34962),
    );
    let a_nrm = w.accessor(
        &f32_bytes(&flat(&g.normals)),
        5126,
        "VEC3",
        count,
        None,
        Some(34962),
    );
    let mut attributes = json!({ "POSITION": a_pos, "NORMAL": a_nrm });
    if let Some(skins) = skins {
        let jb: Vec<u8> = skins
            .iter()
            .flat_map(|(j, _)| j.iter().flat_map(|x| x.to_le_bytes()))
            .collect();
        let wf: Vec<f32> = skins.iter().flat_map(|(_, w)| *w).collect();
        attributes["JOINTS_0"] = json!(w.accessor(&jb, 5123, "VEC4", count, None, Some(34962)));
        attributes["WEIGHTS_0"] =
            json!(w.accessor(&f32_bytes(&wf), 5126, "VEC4", count, None, Some(34962)));
    }
    let indices = if count <= u16::MAX as usize {
        let b: Vec<u8> = g
            .triangles
            .iter()
            .flatten()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect();
        w.accessor(&b, 5123, "SCALAR", g.triangles.len() * 3, None, Some(34963))
    } else {
        let b: Vec<u8> = g
            .triangles
            .iter()
            .flatten()
            .flat_map(|&i| i.to_le_bytes())
            .collect();
        w.accessor(&b, 5125, "SCALAR", g.triangles.len() * 3, None, Some(34963))
    };
    json!({ "attributes": attributes, "indices": indices, "material": material })
}

fn add_to_scene(json: &mut Value, node: usize) {
    if let Some(a) = json["scenes"][0]["nodes"].as_array_mut() {
        a.push(json!(node));
    }
}
