//! The built-in character as a VRM 1.0 avatar file: its skeleton as nodes, its skinned
//! body, its humanoid bones and its strands as VRM spring bones
//! ([`tassel::builtin::avatar`]). An avatar anyone may use and redistribute (it is made
//! here, in code), with meshes and many nodes, for the examples and the benchmarks.

use crate::builtin_look::builtin_body;
use crate::error::GltfError;
use crate::export::{export_glb, BoneMesh, ExportSource};
use crate::vrm_export::VrmAvatar;
use tassel::builtin::{self, avatar};

/// The built-in character (`tassel::builtin::character()`) as a VRM 1.0 GLB: 82 joint
/// nodes and one skinned mesh node, `VRMC_vrm` (meta, humanoid) and `VRMC_springBone`
/// (13 springs, 44 swinging joints, 6 colliders). No animation: it stands in its rest pose.
pub fn builtin_avatar() -> Result<Vec<u8>, GltfError> {
    let c = builtin::character();
    let sk = &c.skeleton;
    let springs = avatar::spring_bones(&c);
    // One strand per spring (the skirt's columns are one sheet, drawn from the skeleton).
    let mut strands: Vec<(String, Vec<usize>)> = Vec::new();
    for s in &springs.springs {
        if s.name.starts_with("skirt") {
            if !strands.iter().any(|(n, _)| n == "skirt") {
                strands.push(("skirt".into(), Vec::new()));
            }
            continue;
        }
        let mut joints: Vec<usize> = s.joints.iter().map(|j| j.joint).collect();
        if let Some(tassel::dynamics::vrm::VrmTail::Joint(t)) = s.joints.last().map(|j| j.tail) {
            joints.push(t);
        }
        strands.push((s.name.clone(), joints));
    }
    let mut source = ExportSource::from_skeleton(sk, BoneMesh::None);
    source.add_body(sk, &builtin_body(sk, &strands))?;
    let humanoid = avatar::HUMANOID
        .iter()
        .filter_map(|(bone, joint)| Some((bone.to_string(), sk.find(joint)?)))
        .collect();
    source.add_vrm(&VrmAvatar {
        name: "Tassel's built-in character".into(),
        authors: vec!["Tassel".into()],
        license_url: "https://vrm.dev/licenses/1.0/".into(),
        humanoid,
        springs,
    })?;
    export_glb(&source, &[])
}
