//! Triangle meshes of a glTF file placed in the scene, e.g. to build a controller level.

use crate::GltfError;
use glam::{Mat4, Vec3};
use gltf::accessor::DataType::{F32, U16, U32, U8};
use gltf::accessor::Dimensions::{self, Scalar};
use tassel::controller::{LevelCollider, LevelShape};
use tassel::Skeleton;

/// One mesh primitive where the file puts it: positions in world space at rest.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshInstance {
    /// The node that holds the mesh.
    pub node: usize,
    /// `"<mesh name>/<primitive index>"`.
    pub name: String,
    /// Vertex positions, world space: the node's rest transform applied; skinned meshes
    /// keep their bind-pose positions (glTF ignores a skinned mesh node's transform).
    pub vertices: Vec<Vec3>,
    /// Three indices per triangle.
    pub indices: Vec<[u32; 3]>,
}

impl MeshInstance {
    /// A static level collider made of this mesh's triangles.
    pub fn to_collider(&self) -> LevelCollider {
        LevelCollider::new(
            self.name.clone(),
            LevelShape::TriMesh {
                vertices: self.vertices.clone(),
                indices: self.indices.clone(),
            },
            Vec3::ZERO,
        )
    }
}

/// Reads every triangle-list primitive of every node with a mesh. Points, lines, strips
/// and fans are skipped with a warning in `warnings`.
pub(crate) fn read_meshes(
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    buffer_len: &dyn Fn(usize) -> usize,
    skeleton: &Skeleton,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
    invalid: &dyn Fn(String) -> GltfError,
) -> Result<Vec<MeshInstance>, GltfError> {
    // Node matrices multiplied down the hierarchy (glTF's rule, shear included).
    let mut models: Vec<Mat4> = Vec::with_capacity(skeleton.len());
    for (j, rest) in skeleton.rest().iter().enumerate() {
        let local = rest.to_mat4();
        let m = match skeleton.parent(j) {
            Some(p) => models[p] * local,
            None => local,
        };
        models.push(m);
    }
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|v| v.as_slice());
    let mut out = Vec::new();
    for node in doc.nodes() {
        let Some(mesh) = node.mesh() else { continue };
        let world: Mat4 = if node.skin().is_some() {
            Mat4::IDENTITY
        } else {
            models[node_to_joint[node.index()]]
        };
        for prim in mesh.primitives() {
            let name = format!("{}/{}", mesh.name().unwrap_or("mesh"), prim.index());
            if prim.mode() != gltf::mesh::Mode::Triangles {
                warnings.push(format!(
                    "mesh '{name}' on node {}: mode {:?} is not a triangle list; not read",
                    node.index(),
                    prim.mode()
                ));
                continue;
            }
            let Some(acc) = prim.get(&gltf::Semantic::Positions) else {
                return Err(invalid(format!("mesh '{name}' has no POSITION")));
            };
            let what = format!("mesh '{name}' POSITION");
            crate::accessor::check(&acc, &[(F32, Dimensions::Vec3)], buffer_len, &what)
                .map_err(invalid)?;
            if let Some(acc) = prim.indices() {
                let what = format!("mesh '{name}' indices");
                let allowed = [(U8, Scalar), (U16, Scalar), (U32, Scalar)];
                crate::accessor::check(&acc, &allowed, buffer_len, &what).map_err(invalid)?;
            }
            let reader = prim.reader(get);
            let Some(positions) = reader.read_positions() else {
                return Err(invalid(format!("mesh '{name}' has no POSITION")));
            };
            let vertices: Vec<Vec3> = positions
                .map(|p| world.transform_point3(Vec3::from(p)))
                .collect();
            let flat: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..vertices.len() as u32).collect(),
            };
            if !flat.len().is_multiple_of(3) {
                return Err(invalid(format!(
                    "mesh '{name}': {} indices is not a whole number of triangles",
                    flat.len()
                )));
            }
            if let Some(&i) = flat.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(invalid(format!(
                    "mesh '{name}': index {i} but only {} vertices",
                    vertices.len()
                )));
            }
            out.push(MeshInstance {
                node: node.index(),
                name,
                indices: flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                vertices,
            });
        }
    }
    Ok(out)
}
