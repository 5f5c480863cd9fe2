//! Compiling rig settings against a skeleton into flat, structure-of-arrays point data.

use super::constraint::{self, Constraints, PointTable};
use super::settings::ChainSettings;
use crate::dynamics::{CompiledCollider, RigSettings};
use crate::error::{Error, Result};
use crate::pose::Pose;
use crate::skeleton::Skeleton;
use std::ops::Range;

/// Marks "no point" in point-index arrays.
pub(crate) const NONE: u32 = u32::MAX;
/// Marks a virtual (dummy tip) point that has no joint.
pub(crate) const VIRTUAL: u16 = u16::MAX;

/// What one simulated point is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PointInfo {
    /// The joint it moves, or `None` for a virtual tip.
    pub joint: Option<usize>,
    /// Index of its parent point, or `None` for a chain root (animated, not simulated).
    pub parent: Option<usize>,
    /// The chain it belongs to.
    pub chain: usize,
}

#[derive(Debug, Clone)]
pub(crate) struct CompiledChain {
    pub settings: ChainSettings,
    pub points: Range<usize>,
    pub colliders: Vec<usize>,
    /// `simulation_space = "base_bone"`: the base bone's joint.
    pub base: Option<usize>,
}

impl CompiledChain {
    /// Whether the chain's settings ask for what only the scalar step does: a simulation
    /// space other than the character's, a move scale, a noisy wind, `kawaii` mode, bone
    /// subdivision.
    pub(crate) fn scalar_only(&self) -> bool {
        let s = &self.settings;
        s.simulation_space != super::SimulationSpace::Component
            || s.skel_comp_move_scale != glam::Vec3::ONE
            || s.wind.direction_noise_angle > 0.0
            || s.mode == super::TimeMode::Kawaii
            || s.bone_subdivision_count > 0
            || s.bone_subdivision_densify_by_radius
    }
}

/// Chains and colliders compiled against one skeleton. Immutable; share it between every
/// character that uses the same skeleton and rig.
#[derive(Debug, Clone)]
pub struct ChainRig {
    pub(crate) chains: Vec<CompiledChain>,
    pub(crate) colliders: Vec<CompiledCollider>,
    // Per point (structure of arrays), chains one after another, parents before children.
    pub(crate) joint: Vec<u16>,
    pub(crate) parent: Vec<u32>,
    /// Per point: its nearest ancestor point that is not a point between bones (NONE for
    /// a root); for a point between bones, the bone it starts from.
    pub(crate) real_parent: Vec<u32>,
    /// Per point between bones (`bone_subdivision_count`): its place on its segment,
    /// 0..1 exclusive (0: not such a point), and the segment's end point.
    pub(crate) inter_alpha: Vec<f32>,
    pub(crate) inter_end: Vec<u32>,
    /// Per point: a point between bones that only collides (carried on its segment).
    pub(crate) carried: Vec<bool>,
    /// Some chain has points between bones.
    pub(crate) subdivided: bool,
    pub(crate) chain_of: Vec<u16>,
    pub(crate) dummy_length: Vec<f32>,
    pub(crate) damping: Vec<f32>,
    pub(crate) stiffness: Vec<f32>,
    pub(crate) radius: Vec<f32>,
    pub(crate) wd_location: Vec<f32>,
    pub(crate) wd_rotation: Vec<f32>,
    pub(crate) limit_angle: Vec<f32>,
    // Write-back: joints that turn toward their simulated children, in joint order.
    pub(crate) rotators: Vec<(u16, u32, Range<u32>)>,
    pub(crate) rotator_children: Vec<u32>,
    /// Twin chains stepped side by side in SIMD lanes (see [`crate::dynamics::chain::lanes::twins`]).
    pub(crate) lane_groups: Vec<crate::dynamics::chain::lanes::twins::ChainLaneGroup>,
    /// The rotators not written back in a lane group's lanes (with the lanes on), in
    /// order.
    pub(crate) scalar_rotators: Vec<u32>,
    /// Per chain: stepped in a lane group (with the lanes on).
    pub(crate) chain_in_lanes: Vec<bool>,
    /// Bone constraints and the chain groups they join.
    pub(crate) constraints: Constraints,
    /// Sync bones, and per chain whether one moves its targets.
    pub(crate) syncs: Vec<super::sync::CompiledSync>,
    pub(crate) synced_chain: Vec<bool>,
    /// Per point: its rest distance from its chain's root over the chain's longest (the
    /// parameter curves' x; KawaiiPhysics' `LengthRateFromRoot`).
    pub(crate) length_rate: Vec<f32>,
    /// The rig file's external forces.
    pub(crate) forces: Vec<std::sync::Arc<super::force::CompiledForce>>,
    pub(crate) joint_count: usize,
    /// The rig's `[[collider_group]]`s: name and collider indices.
    pub(crate) collider_groups: Vec<(String, Vec<usize>)>,
}

impl ChainRig {
    /// Appends a point: joint `joint` (or [`VIRTUAL`]), parent point `parent`, nearest
    /// real ancestor `real_parent`, virtual tip length `dummy_length` (0: none).
    fn push_point(&mut self, joint: u16, parent: u32, real_parent: u32, dummy_length: f32) {
        self.joint.push(joint);
        self.parent.push(parent);
        self.real_parent.push(real_parent);
        self.dummy_length.push(dummy_length);
        self.inter_alpha.push(0.0);
        self.inter_end.push(NONE);
        self.carried.push(false);
    }

    /// The points between bone point `from` and the point about to follow it, `length`
    /// apart at rest (KawaiiPhysics 1.21's `InsertInterBoneDummyBonesCore`):
    /// `bone_subdivision_count` of them, more where `bone_subdivision_densify_by_radius`
    /// asks, none on a segment of no length. Returns the last point (the next one's
    /// parent) and how many were put.
    fn subdivide(
        &mut self,
        s: &ChainSettings,
        from: u32,
        length: f32,
        start: usize,
        rest_dist: &mut Vec<f32>,
    ) -> (u32, usize) {
        // KawaiiPhysics' KINDA_SMALL_NUMBER (1e-4 cm), in metres.
        const SMALL: f32 = 1e-6;
        if length <= SMALL {
            return (from, 0);
        }
        let mut n = s.bone_subdivision_count.min(10) as usize;
        if s.bone_subdivision_densify_by_radius {
            // The radius curve's smallest value over the chain: its ends and its keys
            // within [0, 1] (KawaiiPhysics' conservative estimate).
            let curve = &s.curves.radius;
            let smallest = curve
                .keys
                .iter()
                .filter(|k| (0.0..=1.0).contains(&k[0]))
                .map(|k| k[1])
                .fold(curve.eval(0.0).min(curve.eval(1.0)), f32::min);
            let radius = s.radius * smallest.max(0.0);
            if radius > SMALL {
                let cover = ((length / (2.0 * radius)).ceil() as i64 - 1).max(0) as usize;
                n = n.max(cover);
            }
        }
        let n = n.min(50);
        let mut parent = from;
        for k in 0..n {
            let alpha = (k + 1) as f32 / (n + 1) as f32;
            let idx = self.joint.len() as u32;
            self.push_point(VIRTUAL, parent, from, 0.0);
            self.inter_alpha[idx as usize] = alpha;
            self.carried[idx as usize] = s.bone_subdivision_collision_only;
            rest_dist.push(rest_dist[parent as usize - start] + length / (n + 1) as f32);
            parent = idx;
        }
        (parent, n)
    }

    /// Point `end` ends the segment whose points [`Self::subdivide`] just put.
    fn end_segment(&mut self, end: u32) {
        let mut p = self.parent[end as usize];
        while p != NONE && self.inter_alpha[p as usize] > 0.0 {
            self.inter_end[p as usize] = end;
            p = self.parent[p as usize];
        }
    }

    /// Whether point `p` lies between bones (`bone_subdivision_count`).
    pub(crate) fn is_inter(&self, p: usize) -> bool {
        self.inter_alpha[p] > 0.0
    }

    /// The axis, in the parent joint's space, that point `p`'s planar constraint keeps
    /// its bone perpendicular to (its chain's `planar_constraint`), or `None` when its
    /// chain has none (then no step reads a normal of its).
    pub(crate) fn planar_axis(&self, p: usize) -> Option<glam::Vec3> {
        self.chains[self.chain_of[p] as usize]
            .settings
            .planar_constraint
            .axis()
    }

    /// Every point, chain after chain, with its chain's planar axis ([`Self::planar_axis`],
    /// looked up once per chain rather than per point).
    pub(crate) fn points_and_planar_axes(
        &self,
    ) -> impl Iterator<Item = (usize, Option<glam::Vec3>)> + '_ {
        self.chains.iter().flat_map(|c| {
            let axis = c.settings.planar_constraint.axis();
            c.points.clone().map(move |p| (p, axis))
        })
    }

    /// Compiles `rig` for `skeleton`: resolves bone names, collects each chain's points
    /// depth-first, evaluates the parameter curves. Errors name the chain or collider.
    pub fn new(skeleton: &Skeleton, rig: &RigSettings) -> Result<Self> {
        rig.validate_for(skeleton)?;
        let rig = &*rig.mirrored(skeleton)?;
        let rest = Pose::rest(skeleton);
        let mut pairs = 0usize;
        let mut out = ChainRig {
            chains: Vec::new(),
            colliders: Vec::new(),
            joint: Vec::new(),
            parent: Vec::new(),
            real_parent: Vec::new(),
            inter_alpha: Vec::new(),
            inter_end: Vec::new(),
            carried: Vec::new(),
            subdivided: false,
            chain_of: Vec::new(),
            dummy_length: Vec::new(),
            damping: Vec::new(),
            stiffness: Vec::new(),
            radius: Vec::new(),
            wd_location: Vec::new(),
            wd_rotation: Vec::new(),
            limit_angle: Vec::new(),
            rotators: Vec::new(),
            rotator_children: Vec::new(),
            lane_groups: Vec::new(),
            scalar_rotators: Vec::new(),
            chain_in_lanes: Vec::new(),
            constraints: Constraints::default(),
            syncs: Vec::new(),
            synced_chain: Vec::new(),
            length_rate: Vec::new(),
            forces: Vec::new(),
            joint_count: skeleton.len(),
            collider_groups: Vec::new(),
        };
        // Every point's rest length from its chain's root.
        let mut point_rest_dist: Vec<f32> = Vec::new();
        out.colliders = CompiledCollider::compile_all(skeleton, rig);
        out.collider_groups = rig
            .collider_groups
            .iter()
            .map(|g| (g.name.clone(), rig.collider_indices(&g.colliders)))
            .collect();
        let mut owner: Vec<Option<usize>> = vec![None; skeleton.len()];
        for (ci, settings) in rig.chains.iter().enumerate() {
            let root = skeleton.find(&settings.root).unwrap_or(0);
            let excluded: Vec<usize> = settings
                .exclude
                .iter()
                .filter_map(|e| skeleton.find(e))
                .collect();
            let start = out.joint.len();
            // Depth-first joint order is the skeleton's own order restricted to the subtree.
            let mut point_of = std::collections::HashMap::new();
            let mut rest_dist = Vec::new();
            for j in root..skeleton.len() {
                if !skeleton.is_descendant_of(j, root) {
                    if j > root {
                        // Subtrees are contiguous in depth-first order.
                        break;
                    }
                    continue;
                }
                if excluded.iter().any(|&e| skeleton.is_descendant_of(j, e)) {
                    continue;
                }
                if let Some(other) = owner[j] {
                    return Err(Error::InvalidParameter(format!(
                        "bone '{}' is in chain '{}' and chain '{}'",
                        skeleton.name(j),
                        rig.chains[other].name,
                        settings.name
                    )));
                }
                owner[j] = Some(ci);
                let real_parent = if j == root {
                    NONE
                } else {
                    skeleton
                        .parent(j)
                        .and_then(|p| point_of.get(&p).copied())
                        .unwrap_or(NONE)
                };
                let mut parent = real_parent;
                let mut d = 0.0;
                if real_parent != NONE {
                    let pj = out.joint[real_parent as usize] as usize;
                    let length =
                        (rest.models[j].translation - rest.models[pj].translation).length();
                    parent = out
                        .subdivide(settings, real_parent, length, start, &mut rest_dist)
                        .0;
                    // KawaiiPhysics 1.21 counts a bone's whole length again after the
                    // points before it (its `CalcBoneLength`); `kawaii` mode does too.
                    let from = match settings.mode {
                        super::TimeMode::Kawaii => parent,
                        _ => real_parent,
                    };
                    d = rest_dist[from as usize - start] + length;
                }
                let idx = out.joint.len() as u32;
                point_of.insert(j, idx);
                out.push_point(j as u16, parent, real_parent, 0.0);
                rest_dist.push(d);
                out.end_segment(idx);
            }
            if out.joint.len() - start < 2 && settings.dummy_bone_length <= 0.0 {
                return Err(Error::InvalidParameter(format!(
                    "chain '{}': root '{}' has no bone below it to simulate; give it a dummy_bone_length",
                    settings.name, settings.root
                )));
            }
            // Virtual tips after every leaf.
            if settings.dummy_bone_length > 0.0 {
                let real_end = out.joint.len();
                for p in start..real_end {
                    let is_leaf = out.inter_alpha[p] == 0.0
                        && !(start..real_end).any(|c| out.real_parent[c] == p as u32);
                    if is_leaf {
                        let length = settings.dummy_bone_length;
                        let (parent, n) =
                            out.subdivide(settings, p as u32, length, start, &mut rest_dist);
                        let tip = out.joint.len() as u32;
                        out.push_point(VIRTUAL, parent, p as u32, length);
                        // After points, the tip's own segment (as 1.21 counts it too).
                        rest_dist
                            .push(rest_dist[parent as usize - start] + length / (n + 1) as f32);
                        out.end_segment(tip);
                    }
                }
            }
            let end = out.joint.len();
            out.chain_of.resize(end, ci as u16);
            point_rest_dist.extend_from_slice(&rest_dist);
            let max_dist = rest_dist.iter().cloned().fold(0.0f32, f32::max).max(1e-6);
            for &d in &rest_dist {
                let x = d / max_dist;
                out.length_rate.push(x);
                let v = super::overrides::point_settings(
                    settings,
                    x,
                    &super::overrides::SettingsScale::ONE,
                );
                out.damping.push(v[0]);
                out.stiffness.push(v[1]);
                out.wd_location.push(v[2]);
                out.wd_rotation.push(v[3]);
                out.radius.push(v[4]);
                out.limit_angle.push(v[5]);
            }
            let colliders = rig.collider_indices(&settings.colliders);
            pairs = pairs.saturating_add(colliders.len().saturating_mul(end - start));
            if pairs > crate::limits::MAX_COLLIDER_PAIRS {
                return Err(crate::Error::InvalidParameter(format!(
                    "chain '{}': the chains test more than {} point-collider pairs per step \
                     (the limit)",
                    settings.name,
                    crate::limits::MAX_COLLIDER_PAIRS
                )));
            }
            let base = (settings.simulation_space == super::SimulationSpace::BaseBone)
                .then(|| skeleton.find(&settings.simulation_base_bone))
                .flatten();
            out.chains.push(CompiledChain {
                settings: settings.clone(),
                points: start..end,
                colliders,
                base,
            });
        }
        out.subdivided = out.inter_alpha.iter().any(|&a| a > 0.0);
        // Rotators, in joint order so parents are written before children.
        let mut rot: Vec<(u16, u32, Vec<u32>)> = Vec::new();
        for p in 0..out.joint.len() {
            let parent = out.parent[p];
            if parent == NONE {
                continue;
            }
            let pj = out.joint[parent as usize];
            if pj == VIRTUAL {
                // A point between bones turns no bone (its real bone turns toward the
                // first point after it).
                continue;
            }
            match rot.iter_mut().find(|r| r.1 == parent) {
                Some(r) => r.2.push(p as u32),
                None => rot.push((pj, parent, vec![p as u32])),
            }
        }
        rot.sort_by_key(|r| r.0);
        for (j, p, kids) in rot {
            let s = out.rotator_children.len() as u32;
            out.rotator_children.extend(kids);
            out.rotators
                .push((j, p, s..out.rotator_children.len() as u32));
        }
        out.constraints = out.compile_constraints(skeleton, rig, &rest.models)?;
        out.constraints.all_colliders = (0..out.colliders.len()).collect();
        out.syncs = super::sync::compile(
            skeleton,
            &rig.sync_bones,
            &rest.models,
            &out.joint,
            &out.parent,
            &out.chains,
            &point_rest_dist,
        )?;
        out.synced_chain = vec![false; out.chains.len()];
        for &(p, _) in out.syncs.iter().flat_map(|s| &s.targets) {
            out.synced_chain[out.chain_of[p as usize] as usize] = true;
        }
        if rig.external_forces.len() > crate::limits::MAX_EXTERNAL_FORCES {
            return Err(Error::InvalidParameter(format!(
                "the rig defines {} external forces, more than the limit of {}",
                rig.external_forces.len(),
                crate::limits::MAX_EXTERNAL_FORCES
            )));
        }
        for (i, f) in rig.external_forces.iter().enumerate() {
            if rig.external_forces[..i].iter().any(|g| g.name == f.name) {
                return Err(Error::InvalidParameter(format!(
                    "two external forces are named '{}'",
                    f.name
                )));
            }
            let force = super::force::CompiledForce::new(skeleton, &out, f)?;
            out.forces.push(std::sync::Arc::new(force));
        }
        let parents: Vec<Option<usize>> = (0..skeleton.len()).map(|j| skeleton.parent(j)).collect();
        out.lane_groups = crate::dynamics::chain::lanes::twins::plan(&parents, &out);
        out.chain_in_lanes = vec![false; out.chains.len()];
        for &ci in out.lane_groups.iter().flat_map(|g| &g.chains) {
            out.chain_in_lanes[ci] = true;
        }
        // A rotator is written back in lanes when its chain's group does that.
        let mut lane_write_back = vec![false; out.chains.len()];
        for g in out.lane_groups.iter().filter(|g| g.write_back.is_some()) {
            for &ci in &g.chains {
                lane_write_back[ci] = true;
            }
        }
        let rotator_in_lanes: Vec<bool> = out
            .rotators
            .iter()
            .map(|(_, p, _)| lane_write_back[out.chain_of[*p as usize] as usize])
            .collect();
        out.scalar_rotators = (0..out.rotators.len() as u32)
            .filter(|&r| !rotator_in_lanes[r as usize])
            .collect();
        Ok(out)
    }

    /// The rig's bone constraints resolved against its points (rest lengths from the
    /// skeleton's rest pose `models`).
    fn compile_constraints(
        &self,
        skeleton: &Skeleton,
        rig: &RigSettings,
        models: &[crate::math::Transform],
    ) -> Result<Constraints> {
        let n = self.point_count();
        let mut rest = vec![glam::Vec3::ZERO; n];
        if !rig.bone_constraints.is_empty() {
            let mut normals = vec![glam::Vec3::Y; n];
            let mut placed = vec![
                crate::collide::PlacedCollider {
                    shape: crate::collide::Shape::Plane,
                    transform: crate::math::Transform::IDENTITY,
                };
                self.colliders.len()
            ];
            super::job::gather_targets(
                skeleton,
                self,
                models,
                &mut rest,
                &mut normals,
                &mut placed,
            );
        }
        let table = PointTable {
            joint: &self.joint,
            parent: &self.parent,
            dummy_length: &self.dummy_length,
            inter_alpha: &self.inter_alpha,
            radius: &self.radius,
            chain_of: &self.chain_of,
            rest: &rest,
        };
        constraint::compile(
            skeleton,
            &rig.bone_constraints,
            &rig.bone_constraint_options(),
            &table,
            &self.chains,
        )
    }

    /// Whether the rig file sets external forces (then its chains step per character, not
    /// in a [`crate::crowd::ChainCrowd`]'s lanes).
    pub fn has_external_forces(&self) -> bool {
        !self.forces.is_empty()
    }

    /// Whether any sync bone moves this rig's chain targets (then those chains step per
    /// character, not in a [`crate::crowd::ChainCrowd`]'s lanes).
    pub fn has_sync_bones(&self) -> bool {
        !self.syncs.is_empty()
    }

    /// Whether chain `ci` steps alone on the scalar path: bone constraints join it to
    /// others, or a sync bone moves its targets.
    pub(crate) fn steps_outside_lanes(&self, ci: usize) -> bool {
        self.group_of(ci).is_some()
            || self.synced_chain.get(ci).copied().unwrap_or(false)
            || self.chains[ci].scalar_only()
    }

    /// Whether the rig asks for what a [`crate::crowd::ChainCrowd`] does not step: bone
    /// constraints, sync bones, external forces, a simulation space other than the
    /// character's, a move scale, a noisy wind or `kawaii` mode (such characters step one
    /// [`crate::CharacterSim`] each).
    pub fn needs_per_character(&self) -> bool {
        self.uses_shared_collision()
            || self.has_bone_constraints()
            || self.has_sync_bones()
            || self.has_external_forces()
            || self.chains.iter().any(CompiledChain::scalar_only)
    }

    /// Whether any chain collides with colliders other characters share
    /// (`use_shared_collision`): then the character steps per character in crowds.
    pub fn uses_shared_collision(&self) -> bool {
        self.chains.iter().any(|c| c.settings.use_shared_collision)
    }

    /// The colliders of the rig's `[[collider_group]]` named `name` (indices), if there is
    /// one.
    pub fn collider_group(&self, name: &str) -> Option<&[usize]> {
        self.collider_groups
            .iter()
            .find(|g| g.0 == name)
            .map(|g| g.1.as_slice())
    }

    /// The colliders a character shares: those of the group `group`, or every collider
    /// (`None`). An error names a group the rig does not define.
    pub fn shared_set(&self, group: Option<&str>) -> Result<&[usize]> {
        match group {
            None => Ok(&self.constraints.all_colliders),
            Some(name) => self.collider_group(name).ok_or_else(|| {
                Error::InvalidParameter(format!("the rig has no collider group named '{name}'"))
            }),
        }
    }

    /// Whether any bone constraint joins this rig's chains (then its chains with
    /// constraints step per character, not in a [`crate::crowd::ChainCrowd`]'s lanes).
    pub fn has_bone_constraints(&self) -> bool {
        !self.constraints.list.is_empty()
    }

    /// The chain group chain `ci` steps with, if bone constraints join it to others.
    pub(crate) fn group_of(&self, ci: usize) -> Option<usize> {
        self.constraints
            .group_of
            .get(ci)
            .filter(|&&g| g != u32::MAX)
            .map(|&g| g as usize)
    }

    /// Number of simulated points (chain roots and virtual tips included).
    pub fn point_count(&self) -> usize {
        self.joint.len()
    }

    /// The joints the chains turn (each chain joint with a simulated child, in write-back
    /// order): the local rotations a frame writes, and nothing else.
    pub fn rotator_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.rotators.iter().map(|r| r.0 as usize)
    }

    /// Number of chains.
    pub fn chain_count(&self) -> usize {
        self.chains.len()
    }

    /// Number of joints of the skeleton this rig was compiled for.
    pub fn joint_count(&self) -> usize {
        self.joint_count
    }

    /// The settings of chain `i`.
    pub fn chain_settings(&self, i: usize) -> &ChainSettings {
        &self.chains[i].settings
    }

    /// The point range of chain `i` (panics past the last chain; see
    /// [`get_chain_points`](Self::get_chain_points)).
    pub fn chain_points(&self, i: usize) -> Range<usize> {
        self.chains[i].points.clone()
    }

    /// The point range of chain `i`, or `None` past the last chain.
    pub fn get_chain_points(&self, i: usize) -> Option<Range<usize>> {
        self.chains.get(i).map(|c| c.points.clone())
    }

    /// What point `p` is, or `None` past the last point.
    pub fn get_point(&self, p: usize) -> Option<PointInfo> {
        (p < self.joint.len()).then(|| self.point(p))
    }

    /// What point `p` is.
    pub fn point(&self, p: usize) -> PointInfo {
        let chain = self
            .chains
            .iter()
            .position(|c| c.points.contains(&p))
            .unwrap_or(0);
        PointInfo {
            joint: (self.joint[p] != VIRTUAL).then_some(self.joint[p] as usize),
            parent: (self.parent[p] != NONE).then_some(self.parent[p] as usize),
            chain,
        }
    }

    /// The joints that turn toward simulated children, in joint order, each with the point
    /// it sits on and its first child point (its "tail").
    pub fn rotating_joints(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.rotators.iter().map(|(j, p, kids)| {
            (
                *j as usize,
                *p as usize,
                self.rotator_children[kids.start as usize] as usize,
            )
        })
    }

    /// How many bridge points the bone constraints have (`bone_constraint_subdivision_count`).
    pub fn bridge_count(&self) -> usize {
        self.constraints.bridges.len()
    }

    /// Number of bone constraints, those the rig file lists and those added for virtual
    /// tips and between points between bones.
    pub fn bone_constraint_count(&self) -> usize {
        self.constraints.list.len()
    }

    /// Bone constraint `i`: its two points and their rest distance. `None` past the last.
    pub fn bone_constraint(&self, i: usize) -> Option<(usize, usize, f32)> {
        let c = self.constraints.list.get(i)?;
        Some((c.a as usize, c.b as usize, c.rest))
    }

    /// Bridge point `i`: the two points of its bone constraint, how far from the first
    /// toward the second it lies (0..1), and its radius. `None` past the last.
    pub fn bridge(&self, i: usize) -> Option<(usize, usize, f32, f32)> {
        let b = self.constraints.bridges.get(i)?;
        Some((b.a as usize, b.b as usize, b.alpha, b.radius))
    }

    /// The collision radius of point `p`.
    pub fn point_radius(&self, p: usize) -> f32 {
        self.radius[p]
    }

    /// Number of colliders.
    pub fn collider_count(&self) -> usize {
        self.colliders.len()
    }

    /// The joint collider `c` follows.
    pub fn collider_bone(&self, c: usize) -> usize {
        self.colliders[c].bone
    }

    /// Collider `c` placed for its bone's world transform `bone` (scale ignored): where
    /// it is in the world, as other characters' chains see it
    /// ([`crate::CharacterSim::set_shared_colliders`]).
    pub fn collider_at(&self, c: usize, bone: &crate::Transform) -> crate::collide::PlacedCollider {
        self.colliders[c].place_on(&crate::Transform::from_translation_rotation(
            bone.translation,
            bone.rotation,
        ))
    }

    /// How many lane groups of twin chains (the same points, parameters, settings and
    /// colliders; up to eight side by side in SIMD lanes) a `CharacterSim` steps
    /// together; the other chains run the scalar step.
    pub fn lane_groups(&self) -> usize {
        self.lane_groups.len()
    }

    /// Whether chain `ci` is stepped in a lane group.
    pub(crate) fn in_lane_group(&self, ci: usize) -> bool {
        self.chain_in_lanes.get(ci).copied().unwrap_or(false)
    }

    /// The colliders chain `i` collides with.
    pub fn chain_colliders(&self, i: usize) -> &[usize] {
        &self.chains[i].colliders
    }
}
