//! Reading VRM spring bones from the glTF JSON: `VRMC_springBone` 1.0 (with
//! `VRMC_springBone_extended_collider` 1.0) and VRM 0.x `extensions.VRM.secondaryAnimation`.

use crate::GltfError;
use glam::Vec3;
use serde_json::Value;
use tassel::dynamics::vrm::{
    ConstraintKind, NodeConstraint, VrmCollider, VrmColliderGroup, VrmJoint, VrmShape, VrmSpring,
    VrmSpringBones, VrmTail,
};

/// Which VRM spring-bone definition a file carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VrmVersion {
    /// VRM 0.x `extensions.VRM.secondaryAnimation`.
    V0,
    /// `VRMC_springBone` 1.0.
    V1,
}

/// A model's spring bones, with where they came from.
#[derive(Debug, Clone, PartialEq)]
pub struct VrmInfo {
    /// The definition the springs were read from.
    pub version: VrmVersion,
    /// The springs (joints are skeleton indices).
    pub springs: VrmSpringBones,
}

/// VRM 0.x leaf bones get a tail this far along the bone (UniVRM, three-vrm).
pub const VRM0_TAIL_LENGTH: f32 = 0.07;

/// Reads the spring bones of `json` (a glTF document). `VRMC_springBone` wins over VRM 0.x
/// when a file has both. `node_to_joint` maps glTF nodes to skeleton joints. Returns
/// `Ok(None)` for a file without spring bones; an error ([`GltfError::Invalid`], path
/// `<json>`) names the offending entry.
pub fn read_spring_bones(
    json: &Value,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
) -> Result<Option<VrmInfo>, GltfError> {
    read(json, node_to_joint, warnings).map_err(|m| GltfError::Invalid {
        path: "<json>".into(),
        message: format!("spring bones: {m}"),
    })
}

/// [`read_spring_bones`] with the message alone, for the importer to place in its file.
pub(crate) fn read(
    json: &Value,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
) -> Result<Option<VrmInfo>, String> {
    let ext = &json["extensions"];
    let constraints = read_node_constraints(json, node_to_joint, warnings)?;
    let with = |mut springs: VrmSpringBones, version| {
        springs.node_constraints = constraints.clone();
        Some(VrmInfo { version, springs })
    };
    if let Some(sb) = ext.get("VRMC_springBone") {
        let springs = read_v1(sb, json, node_to_joint, warnings)?;
        return Ok(with(springs, VrmVersion::V1));
    }
    if let Some(sa) = ext.get("VRM").and_then(|v| v.get("secondaryAnimation")) {
        let springs = read_v0(sa, json, node_to_joint, warnings)?;
        return Ok(with(springs, VrmVersion::V0));
    }
    if !constraints.is_empty() {
        return Ok(with(VrmSpringBones::default(), VrmVersion::V1));
    }
    Ok(None)
}

/// `VRMC_node_constraint` 1.0 on the nodes (read when `extensionsUsed` lists it, as
/// three-vrm does): roll, aim or rotation, the first present in that order; an unknown
/// `specVersion` is skipped with a warning, as three-vrm skips it.
fn read_node_constraints(
    json: &Value,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
) -> Result<Vec<NodeConstraint>, String> {
    const NAME: &str = "VRMC_node_constraint";
    let used = json["extensionsUsed"]
        .as_array()
        .is_some_and(|a| a.iter().any(|e| e == NAME));
    if !used {
        return Ok(vec![]);
    }
    let nodes = node_count(json);
    let mut out = vec![];
    for (n, node) in array(json, "nodes", "glTF")?.iter().enumerate() {
        let Some(ext) = node.get("extensions").and_then(|e| e.get(NAME)) else {
            continue;
        };
        let at = format!("nodes[{n}].extensions.{NAME}");
        match ext["specVersion"].as_str() {
            Some("1.0" | "1.0-beta") => {}
            other => {
                warnings.push(format!(
                    "{at}: specVersion {other:?} is not 1.0: the constraint is ignored"
                ));
                continue;
            }
        }
        let c = &ext["constraint"];
        let axis_of = |name: &str, at: &str| -> Result<Vec3, String> {
            Ok(match name {
                "X" | "PositiveX" => Vec3::X,
                "Y" | "PositiveY" => Vec3::Y,
                "Z" | "PositiveZ" => Vec3::Z,
                "NegativeX" => Vec3::NEG_X,
                "NegativeY" => Vec3::NEG_Y,
                "NegativeZ" => Vec3::NEG_Z,
                other => return Err(format!("{at}: unknown axis {other:?}")),
            })
        };
        let (def, kind, cat) = if let Some(r) = c.get("roll").filter(|v| !v.is_null()) {
            let cat = format!("{at}.constraint.roll");
            let name = r["rollAxis"].as_str().unwrap_or("X");
            if !matches!(name, "X" | "Y" | "Z") {
                return Err(format!("{cat}.rollAxis must be X, Y or Z, not {name:?}"));
            }
            let axis = axis_of(name, &cat)?;
            (r, ConstraintKind::Roll { axis }, cat)
        } else if let Some(a) = c.get("aim").filter(|v| !v.is_null()) {
            let cat = format!("{at}.constraint.aim");
            let axis = axis_of(a["aimAxis"].as_str().unwrap_or("PositiveX"), &cat)?;
            (a, ConstraintKind::Aim { axis }, cat)
        } else if let Some(r) = c.get("rotation").filter(|v| !v.is_null()) {
            (
                r,
                ConstraintKind::Rotation,
                format!("{at}.constraint.rotation"),
            )
        } else {
            warnings.push(format!(
                "{at}: no roll, aim or rotation constraint; ignored"
            ));
            continue;
        };
        let source = index(&def["source"], &format!("{cat}.source"), nodes, "node")?;
        let weight = number(def, "weight", &cat, 1.0)?;
        if !(0.0..=1.0).contains(&weight) {
            return Err(format!("{cat}.weight {weight} must be in 0..=1"));
        }
        if source == n {
            return Err(format!("{cat}.source is the node itself"));
        }
        out.push(NodeConstraint {
            destination: node_to_joint[n],
            source: node_to_joint[source],
            kind,
            weight,
        });
    }
    Ok(out)
}

fn array<'a>(v: &'a Value, key: &str, at: &str) -> Result<&'a [Value], String> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(&[]),
        Some(Value::Array(a)) => Ok(a),
        Some(_) => Err(format!("{at}.{key} must be an array")),
    }
}

fn number(v: &Value, key: &str, at: &str, default: f32) -> Result<f32, String> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(default),
        Some(Value::Number(n)) => n
            .as_f64()
            .map(|x| x as f32)
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{at}.{key} is not a finite number")),
        Some(other) => Err(format!("{at}.{key} must be a number, not {other}")),
    }
}

fn index(v: &Value, at: &str, count: usize, what: &str) -> Result<usize, String> {
    let i = v
        .as_u64()
        .ok_or_else(|| format!("{at} must be a {what} index, not {v}"))? as usize;
    if i >= count {
        return Err(format!(
            "{at} names {what} {i}, which does not exist ({count} {what}s)"
        ));
    }
    Ok(i)
}

/// An array of indices below `count`, each checked (`at.key[k]` in messages).
fn indices(v: &Value, key: &str, at: &str, count: usize, what: &str) -> Result<Vec<usize>, String> {
    array(v, key, at)?
        .iter()
        .enumerate()
        .map(|(k, x)| index(x, &format!("{at}.{key}[{k}]"), count, what))
        .collect()
}

fn vec3_array(v: &Value, key: &str, at: &str, default: Vec3) -> Result<Vec3, String> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(default),
        Some(Value::Array(a)) if a.len() == 3 => {
            let mut out = [0.0f32; 3];
            for (o, x) in out.iter_mut().zip(a) {
                *o = x
                    .as_f64()
                    .map(|x| x as f32)
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| format!("{at}.{key} must be 3 finite numbers, not {x}"))?;
            }
            Ok(Vec3::from(out))
        }
        Some(other) => Err(format!("{at}.{key} must be 3 numbers, not {other}")),
    }
}

fn vec3_xyz(v: &Value, key: &str, at: &str, default: Vec3) -> Result<Vec3, String> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(default),
        Some(o @ Value::Object(_)) => {
            let at = format!("{at}.{key}");
            Ok(Vec3::new(
                number(o, "x", &at, 0.0)?,
                number(o, "y", &at, 0.0)?,
                number(o, "z", &at, 0.0)?,
            ))
        }
        Some(other) => Err(format!(
            "{at}.{key} must be an {{x, y, z}} object, not {other}"
        )),
    }
}

fn node_count(json: &Value) -> usize {
    json["nodes"].as_array().map_or(0, Vec::len)
}

fn read_v1(
    sb: &Value,
    json: &Value,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
) -> Result<VrmSpringBones, String> {
    let nodes = node_count(json);
    match sb.get("specVersion").and_then(Value::as_str) {
        Some("1.0") => {}
        Some(v) => warnings.push(format!(
            "VRMC_springBone specVersion '{v}' is not 1.0; read as 1.0"
        )),
        None => warnings.push("VRMC_springBone has no specVersion; read as 1.0".into()),
    }
    let mut out = VrmSpringBones::default();
    for (i, c) in array(sb, "colliders", "VRMC_springBone")?
        .iter()
        .enumerate()
    {
        let at = format!("VRMC_springBone.colliders[{i}]");
        let node = index(
            c.get("node").unwrap_or(&Value::Null),
            &format!("{at}.node"),
            nodes,
            "node",
        )?;
        let extended = c
            .get("extensions")
            .and_then(|e| e.get("VRMC_springBone_extended_collider"));
        let shape = match extended {
            Some(x) => {
                let xat = format!("{at}.extensions.VRMC_springBone_extended_collider");
                match x.get("specVersion").and_then(Value::as_str) {
                    Some("1.0") | Some("1.0-draft") => {}
                    Some(v) => {
                        warnings.push(format!("{xat}: specVersion '{v}' is not 1.0; read as 1.0"))
                    }
                    None => warnings.push(format!(
                        "{xat}: no specVersion (required by the extension); read as 1.0"
                    )),
                }
                read_shape(x.get("shape").unwrap_or(&Value::Null), &xat, true)?
            }
            None => read_shape(c.get("shape").unwrap_or(&Value::Null), &at, false)?,
        };
        out.colliders.push(VrmCollider {
            joint: node_to_joint[node],
            shape,
        });
    }
    for (i, g) in array(sb, "colliderGroups", "VRMC_springBone")?
        .iter()
        .enumerate()
    {
        let at = format!("VRMC_springBone.colliderGroups[{i}]");
        let colliders = indices(g, "colliders", &at, out.colliders.len(), "collider")?;
        out.collider_groups.push(VrmColliderGroup {
            name: g.get("name").and_then(Value::as_str).unwrap_or("").into(),
            colliders,
        });
    }
    for (i, s) in array(sb, "springs", "VRMC_springBone")?.iter().enumerate() {
        let at = format!("VRMC_springBone.springs[{i}]");
        let name = s.get("name").and_then(Value::as_str).unwrap_or("").into();
        let collider_groups = indices(
            s,
            "colliderGroups",
            &at,
            out.collider_groups.len(),
            "collider group",
        )?;
        let center = match s.get("center") {
            None | Some(Value::Null) => None,
            Some(c) => Some(node_to_joint[index(c, &format!("{at}.center"), nodes, "node")?]),
        };
        let entries = array(s, "joints", &at)?;
        let mut read = Vec::with_capacity(entries.len());
        for (k, j) in entries.iter().enumerate() {
            let jat = format!("{at}.joints[{k}]");
            let node = index(
                j.get("node").unwrap_or(&Value::Null),
                &format!("{jat}.node"),
                nodes,
                "node",
            )?;
            read.push(VrmJoint {
                joint: node_to_joint[node],
                tail: VrmTail::Local(Vec3::ZERO),
                hit_radius: number(j, "hitRadius", &jat, 0.0)?,
                stiffness: number(j, "stiffness", &jat, 1.0)?,
                gravity_power: number(j, "gravityPower", &jat, 0.0)?,
                gravity_dir: vec3_array(j, "gravityDir", &jat, Vec3::NEG_Y)?,
                drag_force: number(j, "dragForce", &jat, 0.5)?,
                limit: crate::vrm_limit::read_limit(j, &jat, warnings)?,
            });
        }
        if read.last().is_some_and(|j| j.limit.is_some()) {
            warnings.push(format!(
                "{at}.joints[{}] has a {} but is the spring's last joint (only a tail, it \
                 does not turn): the limit is ignored",
                read.len() - 1,
                crate::vrm_limit::EXTENSION
            ));
        }
        if read.len() < 2 {
            warnings.push(format!(
                "{at} has {} joint(s); a spring needs two (a head and its tail), so nothing swings",
                read.len()
            ));
        }
        // The last joint is only a tail: each joint's tail is the next one.
        let joints = read
            .windows(2)
            .map(|w| VrmJoint {
                tail: VrmTail::Joint(w[1].joint),
                ..w[0]
            })
            .collect();
        out.springs.push(VrmSpring {
            name,
            joints,
            collider_groups,
            center,
        });
    }
    Ok(out)
}

fn read_shape(shape: &Value, at: &str, extended: bool) -> Result<VrmShape, String> {
    let inside = |v: &Value| -> Result<bool, String> {
        match v.get("inside") {
            None | Some(Value::Null) => Ok(false),
            Some(Value::Bool(b)) if extended => Ok(*b),
            Some(Value::Bool(_)) => Err(format!(
                "{at}.shape: 'inside' belongs to VRMC_springBone_extended_collider"
            )),
            Some(o) => Err(format!("{at}.shape.inside must be true or false, not {o}")),
        }
    };
    if let Some(s) = shape.get("sphere") {
        let sat = format!("{at}.shape.sphere");
        return Ok(VrmShape::Sphere {
            offset: vec3_array(s, "offset", &sat, Vec3::ZERO)?,
            radius: number(s, "radius", &sat, 0.0)?,
            inside: inside(s)?,
        });
    }
    if let Some(c) = shape.get("capsule") {
        let cat = format!("{at}.shape.capsule");
        return Ok(VrmShape::Capsule {
            offset: vec3_array(c, "offset", &cat, Vec3::ZERO)?,
            tail: vec3_array(c, "tail", &cat, Vec3::ZERO)?,
            radius: number(c, "radius", &cat, 0.0)?,
            inside: inside(c)?,
        });
    }
    if let Some(p) = shape.get("plane") {
        let pat = format!("{at}.shape.plane");
        if !extended {
            return Err(format!(
                "{pat}: planes belong to VRMC_springBone_extended_collider"
            ));
        }
        return Ok(VrmShape::Plane {
            offset: vec3_array(p, "offset", &pat, Vec3::ZERO)?,
            normal: vec3_array(p, "normal", &pat, Vec3::Z)?,
        });
    }
    Err(format!("{at}.shape has no sphere, capsule or plane"))
}

fn read_v0(
    sa: &Value,
    json: &Value,
    node_to_joint: &[usize],
    warnings: &mut Vec<String>,
) -> Result<VrmSpringBones, String> {
    let nodes = node_count(json);
    let at0 = "VRM.secondaryAnimation";
    let mut out = VrmSpringBones::default();
    for (i, g) in array(sa, "colliderGroups", at0)?.iter().enumerate() {
        let at = format!("{at0}.colliderGroups[{i}]");
        let node = index(
            g.get("node").unwrap_or(&Value::Null),
            &format!("{at}.node"),
            nodes,
            "node",
        )?;
        let mut colliders = Vec::new();
        for (k, c) in array(g, "colliders", &at)?.iter().enumerate() {
            let cat = format!("{at}.colliders[{k}]");
            let offset = vec3_xyz(c, "offset", &cat, Vec3::ZERO)?;
            colliders.push(out.colliders.len());
            out.colliders.push(VrmCollider {
                joint: node_to_joint[node],
                shape: VrmShape::Sphere {
                    // VRM 0.x stores the offset in Unity's left-handed axes: z is negated.
                    offset: Vec3::new(offset.x, offset.y, -offset.z),
                    radius: number(c, "radius", &cat, 0.0)?,
                    inside: false,
                },
            });
        }
        out.collider_groups.push(VrmColliderGroup {
            name: format!("colliderGroup{i}"),
            colliders,
        });
    }
    let node_children = |n: usize| -> Vec<usize> {
        json["nodes"][n]["children"]
            .as_array()
            .map(|c| {
                c.iter()
                    .filter_map(Value::as_u64)
                    .map(|x| x as usize)
                    .filter(|&x| x < nodes)
                    .collect()
            })
            .unwrap_or_default()
    };
    let node_translation = |n: usize| -> Vec3 {
        let node = &json["nodes"][n];
        if let Some(t) = node["translation"].as_array() {
            let v: Vec<f32> = t
                .iter()
                .filter_map(Value::as_f64)
                .map(|x| x as f32)
                .collect();
            if v.len() == 3 {
                return Vec3::new(v[0], v[1], v[2]);
            }
        }
        if let Some(m) = node["matrix"].as_array() {
            let v: Vec<f32> = m
                .iter()
                .filter_map(Value::as_f64)
                .map(|x| x as f32)
                .collect();
            if v.len() == 16 {
                return Vec3::new(v[12], v[13], v[14]);
            }
        }
        Vec3::ZERO
    };
    let mut taken = vec![false; nodes];
    for (i, g) in array(sa, "boneGroups", at0)?.iter().enumerate() {
        let at = format!("{at0}.boneGroups[{i}]");
        let collider_groups = indices(
            g,
            "colliderGroups",
            &at,
            out.collider_groups.len(),
            "collider group",
        )?;
        // center −1 (UniVRM's "none") or absent: world space.
        let center = match g.get("center").and_then(Value::as_i64) {
            Some(c) if c >= 0 => {
                Some(node_to_joint[index(&Value::from(c), &format!("{at}.center"), nodes, "node")?])
            }
            _ => None,
        };
        let template = VrmJoint {
            joint: 0,
            tail: VrmTail::Local(Vec3::ZERO),
            hit_radius: number(g, "hitRadius", &at, 0.02)?,
            stiffness: number(g, "stiffiness", &at, 1.0)?,
            gravity_power: number(g, "gravityPower", &at, 0.0)?,
            gravity_dir: vec3_xyz(g, "gravityDir", &at, Vec3::NEG_Y)?,
            drag_force: number(g, "dragForce", &at, 0.4)?,
            limit: None,
        };
        let mut joints = Vec::new();
        for (k, b) in array(g, "bones", &at)?.iter().enumerate() {
            let root = index(b, &format!("{at}.bones[{k}]"), nodes, "node")?;
            // Depth-first over the root's subtree; every node swings, its first child is its
            // tail, a leaf gets a virtual tail 7 cm along its own bone.
            let mut stack = vec![root];
            let mut guard = 0usize;
            while let Some(n) = stack.pop() {
                guard += 1;
                if guard > nodes {
                    return Err(format!("{at}.bones[{k}]: the node tree has a cycle"));
                }
                let children = node_children(n);
                if taken[n] {
                    warnings.push(format!(
                        "{at}: node {n} already swings in an earlier bone group; kept there"
                    ));
                } else {
                    taken[n] = true;
                    let tail = match children.first() {
                        Some(&c) => VrmTail::Joint(node_to_joint[c]),
                        None => {
                            let t = node_translation(n);
                            let dir = if t.length_squared() > 1e-12 {
                                t.normalize()
                            } else {
                                Vec3::Y
                            };
                            VrmTail::Local(dir * VRM0_TAIL_LENGTH)
                        }
                    };
                    joints.push(VrmJoint {
                        joint: node_to_joint[n],
                        tail,
                        ..template
                    });
                }
                stack.extend(children.iter().rev());
            }
        }
        out.springs.push(VrmSpring {
            name: g
                .get("comment")
                .and_then(Value::as_str)
                .unwrap_or("")
                .into(),
            joints,
            collider_groups,
            center,
        });
    }
    Ok(out)
}
