//! Writing a VRM 1.0 avatar: `VRMC_vrm` (meta and humanoid) and `VRMC_springBone` 1.0 on
//! a document, the inverse of what [`crate::read_spring_bones`] reads.

use crate::error::GltfError;
use crate::export::ExportSource;
use glam::Vec3;
use serde_json::{json, Map};
use tassel::dynamics::vrm::{VrmShape, VrmSpringBones, VrmTail};

/// The human bones VRM 1.0 requires (`humanoid.md` of the VRM 1.0 specification).
pub const VRM1_REQUIRED_BONES: [&str; 15] = [
    "hips",
    "spine",
    "head",
    "leftUpperArm",
    "leftLowerArm",
    "leftHand",
    "rightUpperArm",
    "rightLowerArm",
    "rightHand",
    "leftUpperLeg",
    "leftLowerLeg",
    "leftFoot",
    "rightUpperLeg",
    "rightLowerLeg",
    "rightFoot",
];

/// What [`ExportSource::add_vrm`] writes. Node indices are the document's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VrmAvatar {
    /// `meta.name`.
    pub name: String,
    /// `meta.authors` (at least one).
    pub authors: Vec<String>,
    /// `meta.licenseUrl`; the other meta fields are written as the most open VRM 1.0
    /// allows (anyone may use, redistribute and modify it, credit not needed), except the
    /// violent, sexual, political and antisocial uses, which stay off as VRM's defaults.
    pub license_url: String,
    /// Human bones: VRM 1.0 name (`hips`, `leftUpperArm`, …) and node.
    pub humanoid: Vec<(String, usize)>,
    /// Spring bones: joints, tails, colliders' joints and centres are node indices. Each
    /// spring's joints follow one another (a joint's tail is the next joint), the last
    /// one's tail is a node (VRM 1.0 has no virtual tail). Limits, node constraints, planes
    /// and inside colliders are not written (they need draft or extended extensions).
    pub springs: VrmSpringBones,
}

fn invalid(message: String) -> GltfError {
    GltfError::Invalid {
        path: "<export>".into(),
        message: format!("VRM: {message}"),
    }
}

fn finite(v: Vec3) -> bool {
    v.is_finite()
}

impl ExportSource {
    /// Makes the document a VRM 1.0 avatar: adds `VRMC_vrm` and `VRMC_springBone` (and
    /// lists them in `extensionsUsed`). Errors, before anything is written, name a node out
    /// of range, a human bone missing, repeated or given twice the same node, a spring
    /// whose joints do not follow one another, a tail that is not a node, a value that is
    /// not finite or a negative radius, or a part VRM 1.0's core extensions cannot hold.
    pub fn add_vrm(&mut self, avatar: &VrmAvatar) -> Result<(), GltfError> {
        let nodes = self.json["nodes"].as_array().map_or(0, Vec::len);
        let node = |n: usize, what: &str| {
            if n < nodes {
                Ok(n)
            } else {
                Err(invalid(format!("{what}: node {n} of {nodes}")))
            }
        };
        if avatar.authors.is_empty() {
            return Err(invalid("meta needs at least one author".into()));
        }
        let mut bones = Map::new();
        for (bone, n) in &avatar.humanoid {
            node(*n, &format!("human bone {bone}"))?;
            if bones.contains_key(bone) {
                return Err(invalid(format!("human bone {bone} is given twice")));
            }
            if let Some((other, _)) = avatar.humanoid.iter().find(|(b, m)| m == n && b != bone) {
                return Err(invalid(format!(
                    "human bones {bone} and {other} are both node {n}"
                )));
            }
            bones.insert(bone.clone(), json!({ "node": n }));
        }
        if let Some(missing) = VRM1_REQUIRED_BONES
            .iter()
            .find(|b| !bones.contains_key(**b))
        {
            return Err(invalid(format!(
                "the required human bone {missing} is missing"
            )));
        }
        let sb = &avatar.springs;
        if !sb.node_constraints.is_empty() {
            return Err(invalid(
                "node constraints (VRMC_node_constraint) are not written".into(),
            ));
        }
        let mut colliders = Vec::new();
        for (k, c) in sb.colliders.iter().enumerate() {
            let at = format!("collider {k}");
            let shape = match c.shape {
                VrmShape::Sphere {
                    offset,
                    radius,
                    inside: false,
                } if finite(offset) && radius >= 0.0 => json!({ "sphere": {
                    "offset": offset.to_array(), "radius": radius } }),
                VrmShape::Capsule {
                    offset,
                    tail,
                    radius,
                    inside: false,
                } if finite(offset) && finite(tail) && radius >= 0.0 => json!({ "capsule": {
                    "offset": offset.to_array(), "tail": tail.to_array(), "radius": radius } }),
                VrmShape::Sphere { inside: false, .. }
                | VrmShape::Capsule { inside: false, .. } => {
                    return Err(invalid(format!(
                        "{at}: offset, tail and radius must be finite, the radius ≥ 0"
                    )))
                }
                _ => {
                    return Err(invalid(format!(
                        "{at}: planes and inside colliders need \
                         VRMC_springBone_extended_collider, which is not written"
                    )))
                }
            };
            colliders.push(json!({ "node": node(c.joint, &at)?, "shape": shape }));
        }
        let mut groups = Vec::new();
        for (g, group) in sb.collider_groups.iter().enumerate() {
            if let Some(k) = group.colliders.iter().find(|&&k| k >= colliders.len()) {
                return Err(invalid(format!(
                    "collider group {g}: collider {k} of {}",
                    colliders.len()
                )));
            }
            groups.push(json!({ "name": group.name, "colliders": group.colliders }));
        }
        let mut springs = Vec::new();
        for (s, spring) in sb.springs.iter().enumerate() {
            let at = format!("spring {s} ({})", spring.name);
            if let Some(g) = spring.collider_groups.iter().find(|&&g| g >= groups.len()) {
                return Err(invalid(format!(
                    "{at}: collider group {g} of {}",
                    groups.len()
                )));
            }
            let mut joints = Vec::new();
            for (i, j) in spring.joints.iter().enumerate() {
                let jat = format!("{at} joint {i}");
                let VrmTail::Joint(tail) = j.tail else {
                    return Err(invalid(format!(
                        "{jat}: a virtual tail has no node in VRM 1.0"
                    )));
                };
                if let Some(next) = spring.joints.get(i + 1) {
                    if next.joint != tail {
                        return Err(invalid(format!(
                            "{jat}: its tail is node {tail}, the next joint node {}; a VRM \
                             1.0 spring's joints follow one another",
                            next.joint
                        )));
                    }
                }
                if j.limit.is_some() {
                    return Err(invalid(format!(
                        "{jat}: limits (the VRMC_springBone_limit draft) are not written"
                    )));
                }
                let numbers = [j.hit_radius, j.stiffness, j.gravity_power, j.drag_force];
                if !numbers.iter().all(|x| x.is_finite()) || !finite(j.gravity_dir) {
                    return Err(invalid(format!("{jat}: a value is not finite")));
                }
                if j.hit_radius < 0.0 {
                    return Err(invalid(format!(
                        "{jat}: hit radius {} is negative",
                        j.hit_radius
                    )));
                }
                joints.push(json!({
                    "node": node(j.joint, &jat)?,
                    "hitRadius": j.hit_radius,
                    "stiffness": j.stiffness,
                    "gravityPower": j.gravity_power,
                    "gravityDir": j.gravity_dir.to_array(),
                    "dragForce": j.drag_force,
                }));
                if i + 1 == spring.joints.len() {
                    // The last entry is the tail alone: it does not swing.
                    joints.push(json!({ "node": node(tail, &jat)? }));
                }
            }
            let mut out = json!({
                "name": spring.name,
                "joints": joints,
                "colliderGroups": spring.collider_groups,
            });
            if let Some(c) = spring.center {
                out["center"] = json!(node(c, &format!("{at} center"))?);
            }
            springs.push(out);
        }
        // Everything is checked: write.
        let vrm = json!({
            "specVersion": "1.0",
            "meta": {
                "name": avatar.name,
                "version": "1",
                "authors": avatar.authors,
                "licenseUrl": avatar.license_url,
                "avatarPermission": "everyone",
                "allowExcessivelyViolentUsage": false,
                "allowExcessivelySexualUsage": false,
                "commercialUsage": "corporation",
                "allowPoliticalOrReligiousUsage": false,
                "allowAntisocialOrHateUsage": false,
                "creditNotation": "unnecessary",
                "allowRedistribution": true,
                "modification": "allowModificationRedistribution",
            },
            "humanoid": { "humanBones": bones },
        });
        let spring_bone = json!({
            "specVersion": "1.0",
            "colliders": colliders,
            "colliderGroups": groups,
            "springs": springs,
        });
        let root = self
            .json
            .as_object_mut()
            .ok_or_else(|| invalid("the document is not a JSON object".into()))?;
        let used = root.entry("extensionsUsed").or_insert_with(|| json!([]));
        if let Some(list) = used.as_array_mut() {
            for name in ["VRMC_vrm", "VRMC_springBone"] {
                if !list.iter().any(|v| v == name) {
                    list.push(json!(name));
                }
            }
        }
        let ext = root.entry("extensions").or_insert_with(|| json!({}));
        ext["VRMC_vrm"] = vrm;
        ext["VRMC_springBone"] = spring_bone;
        Ok(())
    }
}
