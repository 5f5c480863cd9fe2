//! The built-in character as a VRM 1.0 avatar's data: its humanoid bones, and its strands
//! (the chains, the skirt's columns and the charm's rope) as VRM spring bones colliding
//! with its colliders. What `tassel demo` writes as `demo.vrm` (with a skinned body), and
//! the avatar the benchmarks and the web example run when no file is given.
//!
//! The springs are not the rig's solvers converted: VRM has one kind of spring, so each
//! strand gets VRM parameters chosen by hand for its kind (hair, tail, skirt, cord), its
//! hit radius from the rig, and one collider group per collider the rig names for it.

use super::Character;
use crate::collide::Shape;
use crate::dynamics::vrm::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmShape, VrmSpring, VrmSpringBones, VrmTail,
};
use crate::dynamics::{ColliderSettings, RigSettings};
use crate::skeleton::Skeleton;
use glam::Vec3;

/// VRM 1.0 human bone names (`VRMC_vrm.humanoid.humanBones`) and the built-in joints
/// they name. Every bone VRM 1.0 requires is here. The character faces +Z (VRM 1.0's
/// forward), so its left side (`_l`) is +X. Its arms hang down: it is not in VRM's T-pose.
pub const HUMANOID: [(&str, &str); 21] = [
    ("hips", "hips"),
    ("spine", "spine"),
    ("chest", "chest"),
    ("neck", "neck"),
    ("head", "head"),
    ("leftShoulder", "shoulder_l"),
    ("leftUpperArm", "upper_arm_l"),
    ("leftLowerArm", "lower_arm_l"),
    ("leftHand", "hand_l"),
    ("rightShoulder", "shoulder_r"),
    ("rightUpperArm", "upper_arm_r"),
    ("rightLowerArm", "lower_arm_r"),
    ("rightHand", "hand_r"),
    ("leftUpperLeg", "thigh_l"),
    ("leftLowerLeg", "shin_l"),
    ("leftFoot", "foot_l"),
    ("leftToes", "toe_l"),
    ("rightUpperLeg", "thigh_r"),
    ("rightLowerLeg", "shin_r"),
    ("rightFoot", "foot_r"),
    ("rightToes", "toe_r"),
];

/// The rig's sphere and capsule colliders as VRM colliders (a capsule from its offset
/// minus half its length along its rotated Y to plus), in the rig's order; other shapes,
/// and colliders on a bone the skeleton lacks, are left out. Returns each kept collider's
/// name beside it.
pub fn vrm_colliders(sk: &Skeleton, colliders: &[ColliderSettings]) -> Vec<(String, VrmCollider)> {
    let mut out = Vec::new();
    for c in colliders {
        let Some(joint) = sk.find(&c.bone) else {
            continue;
        };
        let shape = match c.shape {
            Shape::Sphere { radius, inside } => VrmShape::Sphere {
                offset: c.offset,
                radius,
                inside,
            },
            Shape::Capsule { radius, length } => {
                let axis = c.rotation * Vec3::Y * (0.5 * length);
                VrmShape::Capsule {
                    offset: c.offset - axis,
                    tail: c.offset + axis,
                    radius,
                    inside: false,
                }
            }
            _ => continue,
        };
        out.push((c.name.clone(), VrmCollider { joint, shape }));
    }
    out
}

/// VRM parameters of a strand: stiffness, drag, gravity power.
fn feel(name: &str) -> (f32, f32, f32) {
    match name.split('_').next().unwrap_or("") {
        "ponytail" => (0.8, 0.3, 0.05),
        "lock" => (1.2, 0.4, 0.0),
        "tail" => (1.5, 0.4, 0.0),
        "skirt" => (1.0, 0.5, 0.1),
        // The charm's cord hangs and swings.
        _ => (0.3, 0.2, 1.0),
    }
}

/// The strands of `rig` as (name, joints from the first to the last, hit radius,
/// collider names): each chain from its root down its first children, each cloth
/// column, each rope from its root to its end.
fn strands(sk: &Skeleton, rig: &RigSettings) -> Vec<(String, Vec<usize>, f32, Vec<String>)> {
    let mut out = Vec::new();
    for ch in &rig.chains {
        let Some(root) = sk.find(&ch.root) else {
            continue;
        };
        let mut joints = vec![root];
        while let Some(c) = sk.children(*joints.last().unwrap_or(&root)).next() {
            joints.push(c);
        }
        out.push((ch.name.clone(), joints, ch.radius, ch.colliders.clone()));
    }
    let path = |top: &str, end: &str| -> Option<Vec<usize>> {
        let (top, mut j) = (sk.find(top)?, sk.find(end)?);
        let mut up = vec![j];
        while j != top {
            j = sk.parent(j)?;
            up.push(j);
        }
        up.reverse();
        Some(up)
    };
    for cl in &rig.cloths {
        for [top, end] in &cl.chains {
            if let Some(joints) = path(top, end) {
                let name = top.strip_suffix("_0").unwrap_or(top).to_string();
                out.push((name, joints, cl.radius, cl.colliders.clone()));
            }
        }
    }
    for r in &rig.ropes {
        if let Some(joints) = path(&r.root, &r.end) {
            out.push((r.name.clone(), joints, r.world.radius, r.colliders.clone()));
        }
    }
    out
}

/// The built-in character's strands as VRM spring bones (joint indices are skeleton
/// indices): one spring per strand, every joint but the last swinging toward the next,
/// and one collider group per collider, named as it.
pub fn spring_bones(c: &Character) -> VrmSpringBones {
    let sk = &c.skeleton;
    let named = vrm_colliders(sk, &c.rig.colliders);
    let mut b = VrmSpringBones::default();
    for (k, (name, collider)) in named.iter().enumerate() {
        b.colliders.push(*collider);
        b.collider_groups.push(VrmColliderGroup {
            name: name.clone(),
            colliders: vec![k],
        });
    }
    for (name, joints, radius, colliders) in strands(sk, &c.rig) {
        let (stiffness, drag_force, gravity_power) = feel(&name);
        let joints = joints
            .windows(2)
            .map(|w| VrmJoint {
                joint: w[0],
                tail: VrmTail::Joint(w[1]),
                hit_radius: radius,
                stiffness,
                gravity_power,
                gravity_dir: Vec3::NEG_Y,
                drag_force,
                limit: None,
            })
            .collect();
        let collider_groups = colliders
            .iter()
            .filter_map(|n| named.iter().position(|(m, _)| m == n))
            .collect();
        b.springs.push(VrmSpring {
            name,
            joints,
            collider_groups,
            center: None,
        });
    }
    b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_strand_swings_and_collides_with_what_the_rig_names() {
        let c = crate::builtin::character();
        let b = spring_bones(&c);
        // Counted from the skeleton's construction: ponytail 6 bones, tail 8, two locks
        // of 3, eight skirt columns of 4, the charm's 5; each strand's last is a tail.
        let swinging: usize = b.springs.iter().map(|s| s.joints.len()).sum();
        assert_eq!(swinging, 5 + 7 + 2 * 2 + 8 * 3 + 4);
        assert_eq!(b.springs.len(), 1 + 1 + 2 + 8 + 1);
        // head sphere, torso capsule, thighs and shins.
        assert_eq!(b.colliders.len(), 6);
        let ponytail = b.springs.iter().find(|s| s.name == "ponytail").unwrap();
        let groups: Vec<&str> = ponytail
            .collider_groups
            .iter()
            .map(|&g| b.collider_groups[g].name.as_str())
            .collect();
        assert_eq!(groups, ["head", "torso"]);
        // Each joint's tail is its child in the skeleton.
        for s in &b.springs {
            for j in &s.joints {
                let VrmTail::Joint(t) = j.tail else {
                    panic!("local tail")
                };
                assert_eq!(c.skeleton.parent(t), Some(j.joint));
            }
        }
    }

    #[test]
    fn humanoid_bones_exist_and_left_is_plus_x() {
        let c = crate::builtin::character();
        for (_, joint) in HUMANOID {
            assert!(c.skeleton.find(joint).is_some(), "{joint}");
        }
        // (That every bone VRM 1.0 requires is there, `ExportSource::add_vrm` checks
        // when the avatar is written: tassel-gltf's tests/vrm_export.rs.)
        // The left side is +X when facing +Z.
        let rest = crate::Pose::rest(&c.skeleton);
        let hand = |n| rest.models[c.skeleton.find(n).unwrap()].translation.x;
        assert!(hand("hand_l") > 0.0 && hand("hand_r") < 0.0);
    }
}
