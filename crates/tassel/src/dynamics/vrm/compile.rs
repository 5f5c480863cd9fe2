//! Compiling VRM spring bones for a skeleton: one link per simulated joint, in the order
//! the update must visit them (ancestors first), with the rest data the spec's
//! initialisation records.

use super::limit::LinkLimit;
use super::settings::{VrmOptions, VrmShape, VrmSpringBones, VrmTail};
use crate::error::Result;
use crate::math::{normalize_or, Transform};
use crate::pose::Pose;
use crate::skeleton::Skeleton;
use glam::Vec3;
use std::ops::Range;

/// One simulated joint, compiled.
#[derive(Debug, Clone, PartialEq)]
pub struct VrmLink {
    /// The joint that turns.
    pub joint: usize,
    /// Its parent joint (`None` at a skeleton root: the character transform is the parent).
    pub parent: Option<usize>,
    /// The tail joint, when the tail is a joint.
    pub tail_joint: Option<usize>,
    /// The tail in the joint's rest local space.
    pub tail_local: Vec3,
    /// `tail_local` normalised: the spec's `boneAxis`.
    pub bone_axis: Vec3,
    /// The joint's rest local transform (`initialLocalMatrix`, `initialLocalRotation`).
    pub rest_local: Transform,
    /// Index of the spring in the settings.
    pub spring: usize,
    /// Tail sphere radius, metres.
    pub hit_radius: f32,
    /// Stiffness, 1/s.
    pub stiffness: f32,
    /// Gravity direction × power, world, m/s.
    pub gravity: Vec3,
    /// Drag, 0..=1.
    pub drag_force: f32,
    /// Centre joint of the spring.
    pub center: Option<usize>,
    /// Range in [`VrmRig::link_colliders`].
    pub colliders: Range<usize>,
    /// The joint's swing limit (`VRMC_springBone_limit`), compiled.
    pub limit: Option<LinkLimit>,
}

/// VRM spring bones compiled for one skeleton. Shareable between characters.
///
/// The fields describe the compiled rig: read them; to change a parameter, compile again
/// with [`VrmRig::new`] (the plans derived from them, such as the SIMD lane rows, are made
/// there).
#[derive(Debug, Clone, PartialEq)]
pub struct VrmRig {
    /// Links in processing order (ascending joint index: every ancestor before its
    /// descendants).
    pub links: Vec<VrmLink>,
    /// Collider shapes and their joints.
    pub colliders: Vec<(usize, VrmShape)>,
    /// Collider indices of each link, in group order (a collider listed twice is there
    /// twice).
    pub link_colliders: Vec<usize>,
    /// Solver options.
    pub options: VrmOptions,
    /// The file's node constraints, in evaluation order.
    pub(crate) constraints: super::constraint::CompiledConstraints,
    /// The links as SIMD lane rows (several springs side by side), where the rig allows.
    pub(crate) lanes: Option<crate::dynamics::vrm::lanes::springs::SpringLanes>,
    joint_count: usize,
    /// Whether a link has a limit (read every frame: found once here).
    limited: bool,
}

impl VrmRig {
    /// Validates `bones` for `skeleton` and compiles them.
    pub fn new(skeleton: &Skeleton, bones: &VrmSpringBones, options: VrmOptions) -> Result<Self> {
        bones.validate_for(skeleton)?;
        options.validate()?;
        let rest = Pose::rest(skeleton);
        let mut links = Vec::new();
        let mut link_colliders = Vec::new();
        for (si, s) in bones.springs.iter().enumerate() {
            // Every listed collider, in group order: one the spring lists twice (through
            // two groups) acts twice, as the specification, three-vrm and UniVRM apply it.
            let cols: Vec<usize> = s
                .collider_groups
                .iter()
                .flat_map(|&g| bones.collider_groups[g].colliders.iter().copied())
                .collect();
            for j in &s.joints {
                let (tail_joint, tail_local) = match j.tail {
                    VrmTail::Joint(t) => (
                        Some(t),
                        rest.models[t]
                            .relative_to(&rest.models[j.joint])
                            .translation,
                    ),
                    VrmTail::Local(p) => (None, p),
                };
                let bone_axis = normalize_or(tail_local, Vec3::Y);
                let rest_local = skeleton.rest()[j.joint];
                let start = link_colliders.len();
                link_colliders.extend_from_slice(&cols);
                links.push(VrmLink {
                    joint: j.joint,
                    parent: skeleton.parent(j.joint),
                    tail_joint,
                    tail_local,
                    bone_axis,
                    rest_local,
                    spring: si,
                    hit_radius: j.hit_radius,
                    stiffness: j.stiffness,
                    gravity: j.gravity_dir * j.gravity_power,
                    drag_force: j.drag_force,
                    center: s.center,
                    colliders: start..link_colliders.len(),
                    limit: j
                        .limit
                        .map(|lim| LinkLimit::new(&lim, rest_local.rotation, bone_axis)),
                });
            }
        }
        // Ancestors first: the skeleton is depth-first, so a stable sort by joint index
        // puts every joint after all of its ancestors (within and across springs).
        links.sort_by_key(|l| l.joint);
        let mut rig = Self {
            links,
            colliders: bones.colliders.iter().map(|c| (c.joint, c.shape)).collect(),
            link_colliders,
            options,
            constraints: super::constraint::CompiledConstraints::new(
                skeleton,
                &bones.node_constraints,
            )?,
            lanes: None,
            joint_count: skeleton.len(),
            limited: false,
        };
        rig.limited = rig.links.iter().any(|l| l.limit.is_some());
        rig.lanes = crate::dynamics::vrm::lanes::springs::SpringLanes::new(skeleton, &rig);
        Ok(rig)
    }

    /// Whether a link has a swing limit (`VRMC_springBone_limit`).
    pub fn has_limits(&self) -> bool {
        self.limited
    }

    /// Whether the rig has `VRMC_node_constraint` constraints (they turn joints that are
    /// not spring joints, from the animated pose, before the springs).
    pub fn has_node_constraints(&self) -> bool {
        !self.constraints.list.is_empty()
    }

    /// Number of skeleton joints the rig was compiled for.
    pub fn joint_count(&self) -> usize {
        self.joint_count
    }

    /// How many lane groups (up to 16 springs side by side in SIMD lanes on x86_64, 4 in
    /// WebAssembly, 8 elsewhere) the update
    /// runs in; 0 when the rig's shape keeps it on the scalar update (a spring joint at a
    /// skeleton root, a spring hanging below a simulated joint that is not itself a
    /// spring joint, a centre that a spring moves). Either way the results are the same.
    pub fn lane_groups(&self) -> usize {
        self.lanes.as_ref().map_or(0, |l| l.groups())
    }

    /// The lane plan when the job runs it (`SpringLanes::runs_with(simd)`) and no node
    /// constraint runs before it: then the job reads, of the models it is given, only
    /// those of the plan's input joints (`SpringLanes::compose_input`).
    pub(crate) fn lanes_for(
        &self,
        simd: crate::lanes::SimdUse,
    ) -> Option<&crate::dynamics::vrm::lanes::springs::SpringLanes> {
        let runs = self.constraints.list.is_empty();
        self.lanes.as_ref().filter(|l| runs && l.runs_with(simd))
    }

    /// True when nothing is simulated.
    pub fn is_empty(&self) -> bool {
        self.links.is_empty() && self.constraints.list.is_empty()
    }

    /// The joints the rig writes: the springs' joints in processing order, then the node
    /// constraints' destinations in evaluation order.
    pub fn simulated_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.links
            .iter()
            .map(|l| l.joint)
            .chain(self.constraints.list.iter().map(|c| c.0.destination))
    }
}
