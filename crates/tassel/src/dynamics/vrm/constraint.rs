//! VRMC_node_constraint 1.0: a node's rotation driven by another node's, evaluated on the
//! animated pose before the spring bones, as three-vrm's node-constraint package does.
//!
//! - **Rotation**: the destination takes the source's rotation from its rest pose (local
//!   rotations): `dst = dstRest · srcRest⁻¹ · src`.
//! - **Roll**: only the part of that rotation that twists about the roll axis (local X, Y
//!   or Z of the destination's rest frame): the delta seen from the destination's rest
//!   frame, turned back by the swing that moves the axis.
//! - **Aim**: the destination's aim axis (±X, ±Y, ±Z of its rest rotation, under its
//!   parent's current world rotation) turns to point at the source's world position.
//!
//! Each blends from the destination's rest rotation by `weight` (0..=1, spherical). A
//! constraint is evaluated after the constraints that move its source (or the source's
//! ancestors; for aim also the destination's parent's); a cycle is an error.

use crate::error::{Error, Result};
use crate::math::{normalize_or, rotation_arc, slerp_shortest, Transform};
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// What a node constraint does.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ConstraintKind {
    /// The destination rolls with the source's twist about `axis` (a unit local axis of
    /// the destination's rest frame: X, Y or Z).
    Roll {
        /// The roll axis.
        axis: Vec3,
    },
    /// The destination's `axis` (a unit local axis of its rest rotation: ±X, ±Y or ±Z)
    /// points at the source.
    Aim {
        /// The aim axis.
        axis: Vec3,
    },
    /// The destination takes the source's rotation from its rest.
    Rotation,
}

/// One `VRMC_node_constraint` (the extension on the destination node).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NodeConstraint {
    /// The joint the constraint turns.
    pub destination: usize,
    /// The joint it follows.
    pub source: usize,
    /// Roll, aim or rotation.
    pub kind: ConstraintKind,
    /// How much of the constrained rotation is applied, 0..=1.
    pub weight: f32,
}

impl NodeConstraint {
    /// Checks joints, weight and axis against a skeleton of `joints` joints; errors name
    /// the constraint.
    pub fn validate(&self, index: usize, joints: usize) -> Result<()> {
        let bad = |m: String| {
            Err(Error::InvalidParameter(format!(
                "node constraint {index}: {m}"
            )))
        };
        if self.destination >= joints || self.source >= joints {
            return bad(format!(
                "destination {} or source {} is not a joint (the skeleton has {joints})",
                self.destination, self.source
            ));
        }
        if self.destination == self.source {
            return bad(format!("joint {} constrains itself", self.source));
        }
        if !(self.weight.is_finite() && (0.0..=1.0).contains(&self.weight)) {
            return bad(format!("weight {} must be in 0..=1", self.weight));
        }
        if let ConstraintKind::Roll { axis } | ConstraintKind::Aim { axis } = self.kind {
            if !(axis.is_finite() && (axis.length() - 1.0).abs() < 1e-4) {
                return bad(format!("axis {axis} must be a unit vector"));
            }
        }
        Ok(())
    }
}

/// Constraints in evaluation order, with the rest rotations they need.
#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct CompiledConstraints {
    pub list: Vec<(NodeConstraint, Quat, Quat)>,
}

impl CompiledConstraints {
    /// Orders `constraints` so that each comes after those that move what it reads.
    pub fn new(skeleton: &Skeleton, constraints: &[NodeConstraint]) -> Result<Self> {
        for (i, c) in constraints.iter().enumerate() {
            c.validate(i, skeleton.len())?;
        }
        // The constraint driving each joint, if any.
        let mut driven_by = vec![None; skeleton.len()];
        for (i, c) in constraints.iter().enumerate() {
            if driven_by[c.destination].replace(i).is_some() {
                return Err(Error::InvalidParameter(format!(
                    "node constraint {i}: joint {} already has a constraint",
                    c.destination
                )));
            }
        }
        // What a constraint reads: its source and the source's ancestors; for aim also the
        // destination's ancestors (its parent's world rotation and its own position).
        let reads = |c: &NodeConstraint| {
            let mut joints = vec![];
            let mut j = Some(c.source);
            while let Some(k) = j {
                joints.push(k);
                j = skeleton.parent(k);
            }
            if matches!(c.kind, ConstraintKind::Aim { .. }) {
                let mut j = skeleton.parent(c.destination);
                while let Some(k) = j {
                    joints.push(k);
                    j = skeleton.parent(k);
                }
            }
            joints
        };
        let (mut order, mut state) = (Vec::new(), vec![0u8; constraints.len()]);
        fn visit(
            i: usize,
            constraints: &[NodeConstraint],
            driven_by: &[Option<usize>],
            reads: &dyn Fn(&NodeConstraint) -> Vec<usize>,
            state: &mut [u8],
            order: &mut Vec<usize>,
        ) -> Result<()> {
            match state[i] {
                2 => return Ok(()),
                1 => {
                    return Err(Error::InvalidParameter(format!(
                        "node constraint {i}: circular dependency between constraints"
                    )))
                }
                _ => {}
            }
            state[i] = 1;
            for j in reads(&constraints[i]) {
                if let Some(d) = driven_by[j] {
                    visit(d, constraints, driven_by, reads, state, order)?;
                }
            }
            state[i] = 2;
            order.push(i);
            Ok(())
        }
        for i in 0..constraints.len() {
            visit(i, constraints, &driven_by, &reads, &mut state, &mut order)?;
        }
        let rest = skeleton.rest();
        Ok(Self {
            list: order
                .into_iter()
                .map(|i| {
                    let c = constraints[i];
                    (c, rest[c.destination].rotation, rest[c.source].rotation)
                })
                .collect(),
        })
    }

    /// Applies every constraint to `locals` (rotations of the destinations) and keeps
    /// `models` (the model pose of `locals`) up to date; `component` is the character's
    /// world transform (aim reads world positions).
    pub fn apply(
        &self,
        skeleton: &Skeleton,
        component: &Transform,
        locals: &mut [Transform],
        models: &mut [Transform],
    ) {
        for &(c, dst_rest, src_rest) in &self.list {
            let (d, s) = (c.destination, c.source);
            let target = match c.kind {
                ConstraintKind::Rotation => dst_rest * (src_rest.inverse() * locals[s].rotation),
                ConstraintKind::Roll { axis } => {
                    // The source's delta seen from the destination's rest frame, then the
                    // swing that moves the roll axis taken out: only the twist is left.
                    let delta =
                        dst_rest.inverse() * locals[s].rotation * src_rest.inverse() * dst_rest;
                    let swing_back = rotation_arc(normalize_or(delta * axis, axis), axis);
                    dst_rest * swing_back * delta
                }
                ConstraintKind::Aim { axis } => {
                    let parent = match skeleton.parent(d) {
                        Some(p) => (*component * models[p]).rotation,
                        None => component.rotation,
                    };
                    let from = parent * (dst_rest * axis);
                    let to =
                        (*component * models[s]).translation - (*component * models[d]).translation;
                    let turn = rotation_arc(from, normalize_or(to, from));
                    parent.inverse() * turn * parent * dst_rest
                }
            };
            locals[d].rotation = slerp_shortest(dst_rest, target.normalize(), c.weight).normalize();
            // The destination and everything after it in depth-first order.
            for k in d..skeleton.len() {
                models[k] = match skeleton.parent(k) {
                    Some(p) => models[p] * locals[k],
                    None => locals[k],
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pose::Pose;

    /// root → a (1 m up) → b; root → c (1 m along X).
    fn skeleton() -> Skeleton {
        Skeleton::new(
            vec!["root".into(), "a".into(), "b".into(), "c".into()],
            vec![None, Some(0), Some(1), Some(0)],
            vec![
                Transform::IDENTITY,
                Transform::from_translation(Vec3::Y),
                Transform::from_translation(Vec3::Y),
                Transform::from_translation(Vec3::X),
            ],
        )
        .unwrap()
    }

    fn run(sk: &Skeleton, cs: &[NodeConstraint], src_rotation: Quat, src: usize) -> Pose {
        let compiled = CompiledConstraints::new(sk, cs).unwrap();
        let mut pose = Pose::rest(sk);
        pose.locals[src].rotation = src_rotation;
        pose.update_models(sk, &Transform::IDENTITY).unwrap();
        let (locals, models) = (&mut pose.locals, &mut pose.models);
        compiled.apply(sk, &Transform::IDENTITY, locals, models);
        pose
    }

    #[test]
    fn rotation_copies_the_sources_turn_by_weight() {
        let sk = skeleton();
        let turn = Quat::from_rotation_z(0.8);
        for (weight, angle) in [(1.0, 0.8), (0.5, 0.4), (0.0, 0.0)] {
            let c = NodeConstraint {
                destination: 3,
                source: 1,
                kind: ConstraintKind::Rotation,
                weight,
            };
            let pose = run(&sk, &[c], turn, 1);
            let got = pose.locals[3].rotation;
            assert!(
                got.angle_between(Quat::from_rotation_z(angle)) < 1e-5,
                "{weight}: {got}"
            );
        }
    }

    #[test]
    fn roll_keeps_only_the_twist_about_the_axis() {
        let sk = skeleton();
        // Source: 0.6 rad of twist about Y, then a 0.5 rad swing about X.
        let src = Quat::from_rotation_x(0.5) * Quat::from_rotation_y(0.6);
        let c = NodeConstraint {
            destination: 3,
            source: 1,
            kind: ConstraintKind::Roll { axis: Vec3::Y },
            weight: 1.0,
        };
        let got = run(&sk, &[c], src, 1).locals[3].rotation;
        // By hand: the swing-twist split of src about Y has twist exactly 0.6 rad about Y.
        assert!(
            got.angle_between(Quat::from_rotation_y(0.6)) < 1e-5,
            "{got}"
        );
    }

    #[test]
    fn aim_points_the_axis_at_the_source() {
        let sk = skeleton();
        // c aims its +Y at b (at (0, 2, 0); c is at (1, 0, 0)); a is turned so that b
        // moves, and the constraint must follow it.
        let c = NodeConstraint {
            destination: 3,
            source: 2,
            kind: ConstraintKind::Aim { axis: Vec3::Y },
            weight: 1.0,
        };
        let pose = run(&sk, &[c], Quat::from_rotation_z(0.3), 1);
        let b = pose.models[2].translation;
        let aim = pose.models[3].rotation * Vec3::Y;
        let want = (b - pose.models[3].translation).normalize();
        assert!(aim.abs_diff_eq(want, 1e-5), "{aim} vs {want}");
    }

    #[test]
    fn order_follows_dependencies_and_cycles_are_errors() {
        let sk = skeleton();
        // c follows a, b follows c: b must come after c whatever the list order.
        let first = NodeConstraint {
            destination: 2,
            source: 3,
            kind: ConstraintKind::Rotation,
            weight: 1.0,
        };
        let second = NodeConstraint {
            destination: 3,
            source: 1,
            kind: ConstraintKind::Rotation,
            weight: 1.0,
        };
        let compiled = CompiledConstraints::new(&sk, &[first, second]).unwrap();
        assert_eq!(compiled.list[0].0, second);
        let pose = run(&sk, &[first, second], Quat::from_rotation_z(0.5), 1);
        assert!(
            pose.locals[2]
                .rotation
                .angle_between(Quat::from_rotation_z(0.5))
                < 1e-5
        );
        let cycle = NodeConstraint {
            destination: 1,
            source: 3,
            kind: ConstraintKind::Rotation,
            weight: 1.0,
        };
        let err = CompiledConstraints::new(&sk, &[second, cycle]).unwrap_err();
        assert!(err.to_string().contains("circular"), "{err}");
        let bad = NodeConstraint {
            weight: 2.0,
            ..second
        };
        assert!(CompiledConstraints::new(&sk, &[bad])
            .unwrap_err()
            .to_string()
            .contains("weight"));
    }
}
