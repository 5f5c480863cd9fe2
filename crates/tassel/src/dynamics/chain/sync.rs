//! Sync bones after KawaiiPhysics 1.20 (`FKawaiiPhysicsSyncBone`): simulated bones whose
//! animated targets take a share of a source bone's translation from its rest place — a
//! skirt's front columns pushed forward by the thigh, so they do not pass through the leg.
//! Applied to the chains' targets each frame, before the step (see docs/chains.md).

use super::compile::{CompiledChain, NONE};
use crate::dynamics::Curve;
use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Which sign of a source's movement along one axis the targets take
/// (`ESyncBoneDirection`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SyncDirection {
    /// Both signs.
    #[default]
    Both,
    /// Only movement toward +axis.
    Positive,
    /// Only movement toward −axis.
    Negative,
    /// None along this axis.
    None,
}

impl SyncDirection {
    fn keeps(self, v: f32) -> bool {
        match self {
            SyncDirection::Both => true,
            SyncDirection::Positive => v > 0.0,
            SyncDirection::Negative => v < 0.0,
            SyncDirection::None => false,
        }
    }
}

/// A bone that takes the source's movement, with (by default) the bones below it in its
/// chain (`FKawaiiPhysicsSyncTargetRoot`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SyncTargetSettings {
    /// The bone: simulated by a chain, or a chain's root (which stays animated: then only
    /// the bones below it take the movement).
    pub bone: String,
    /// Its descendants in the chain take the movement too.
    pub include_child_bones: bool,
    /// The share each target takes over its length rate from this bone (0 here, 1 at the
    /// farthest tip below it); empty: all of it.
    #[serde(skip_serializing_if = "curve_is_empty")]
    pub scale_curve_by_bone_length_rate: Curve,
}

impl Default for SyncTargetSettings {
    fn default() -> Self {
        Self {
            bone: String::new(),
            include_child_bones: true,
            scale_curve_by_bone_length_rate: Curve::default(),
        }
    }
}

fn curve_is_empty(c: &Curve) -> bool {
    c.keys.is_empty()
}

/// One `[[sync_bone]]` entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SyncBoneSettings {
    /// The source bone (animated): its model-space movement from its rest place is what
    /// the targets take.
    pub bone: String,
    /// The targets (`[[sync_bone.target_root]]`).
    #[serde(rename = "target_root")]
    pub target_roots: Vec<SyncTargetSettings>,
    /// Per model-space axis, the share of the movement applied (0..=1).
    pub global_scale: Vec3,
    /// A factor over the movement's length (metres); empty: 1.
    #[serde(skip_serializing_if = "curve_is_empty")]
    pub scale_curve_by_delta_distance: Curve,
    /// Which signs of the movement along model X the targets take.
    pub apply_direction_x: SyncDirection,
    /// The same along Y.
    pub apply_direction_y: SyncDirection,
    /// The same along Z.
    pub apply_direction_z: SyncDirection,
    /// Attenuate by the distance from the source to each target's simulated point.
    pub enable_distance_attenuation: bool,
    /// No attenuation within this distance, metres.
    pub attenuation_inner_radius: f32,
    /// Full attenuation (`max_attenuation_rate`) from this distance, metres.
    pub attenuation_outer_radius: f32,
    /// The attenuation at and past the outer radius: 0 none, 1 all of the movement.
    pub max_attenuation_rate: f32,
}

impl Default for SyncBoneSettings {
    fn default() -> Self {
        Self {
            bone: String::new(),
            target_roots: Vec::new(),
            global_scale: Vec3::ONE,
            scale_curve_by_delta_distance: Curve::default(),
            apply_direction_x: SyncDirection::Both,
            apply_direction_y: SyncDirection::Both,
            apply_direction_z: SyncDirection::Both,
            enable_distance_attenuation: false,
            attenuation_inner_radius: 0.0,
            attenuation_outer_radius: 0.0,
            max_attenuation_rate: 1.0,
        }
    }
}

impl SyncBoneSettings {
    /// Checks ranges (`n`: the entry's 1-based place in the rig file).
    pub(crate) fn validate(&self, n: usize) -> Result<()> {
        let what = format!("sync_bone #{n} ('{}')", self.bone);
        let bad = |m: String| Err(Error::InvalidParameter(format!("{what}: {m}")));
        if self.target_roots.is_empty() {
            return bad("no target_root".into());
        }
        if !(self.global_scale.is_finite()
            && self.global_scale.min_element() >= 0.0
            && self.global_scale.max_element() <= 1.0)
        {
            return bad(format!(
                "global_scale {} must be within 0..=1 on every axis",
                self.global_scale
            ));
        }
        for (key, v) in [
            ("attenuation_inner_radius", self.attenuation_inner_radius),
            ("attenuation_outer_radius", self.attenuation_outer_radius),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{key} = {v} must be finite and ≥ 0"));
            }
        }
        if !(0.0..=1.0).contains(&self.max_attenuation_rate) {
            return bad(format!(
                "max_attenuation_rate = {} must be within 0..=1",
                self.max_attenuation_rate
            ));
        }
        self.scale_curve_by_delta_distance
            .validate(&format!("{what} scale_curve_by_delta_distance"))?;
        for t in &self.target_roots {
            t.scale_curve_by_bone_length_rate.validate(&format!(
                "{what} target_root '{}' scale_curve_by_bone_length_rate",
                t.bone
            ))?;
        }
        Ok(())
    }
}

/// A compiled sync bone.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CompiledSync {
    pub bone: usize,
    /// Its model-space place in the rest pose.
    pub rest: Vec3,
    pub settings: SyncBoneSettings,
    /// (point, scale by length rate), parents before children.
    pub targets: Vec<(u32, f32)>,
}

/// Resolves `entries` against the chains' points (`rest_dist`: each point's rest length
/// from its chain's root).
pub(crate) fn compile(
    skeleton: &Skeleton,
    entries: &[SyncBoneSettings],
    rest_models: &[crate::math::Transform],
    joint: &[u16],
    parent: &[u32],
    chains: &[CompiledChain],
    rest_dist: &[f32],
) -> Result<Vec<CompiledSync>> {
    let mut out = Vec::with_capacity(entries.len());
    for (i, e) in entries.iter().enumerate() {
        e.validate(i + 1)?;
        let what = format!("sync_bone #{} ('{}')", i + 1, e.bone);
        let bone = skeleton.find(&e.bone).ok_or_else(|| Error::MissingBone {
            context: what.clone(),
            name: e.bone.clone(),
        })?;
        let mut targets = Vec::new();
        for t in &e.target_roots {
            let j = skeleton.find(&t.bone).ok_or_else(|| Error::MissingBone {
                context: format!("{what} target_root"),
                name: t.bone.clone(),
            })?;
            let Some(root) = (0..joint.len()).find(|&p| joint[p] as usize == j) else {
                return Err(Error::InvalidParameter(format!(
                    "{what}: target_root '{}' is in no chain",
                    t.bone
                )));
            };
            let chain = chains
                .iter()
                .find(|c| c.points.contains(&root))
                .map(|c| c.points.clone())
                .unwrap_or(root..root + 1);
            // The root and, with its children, every point below it (chains hold
            // parents before children).
            let mut below = vec![false; chain.len()];
            below[root - chain.start] = true;
            let mut members = vec![root];
            if t.include_child_bones {
                for p in chain.clone().skip(root - chain.start + 1) {
                    let pp = parent[p];
                    if pp != NONE && below[pp as usize - chain.start] {
                        below[p - chain.start] = true;
                        members.push(p);
                    }
                }
            }
            let start = rest_dist[root];
            let max = members.iter().map(|&p| rest_dist[p]).fold(start, f32::max);
            let range = max - start;
            for p in members {
                // A chain's root stays animated: it takes nothing.
                if parent[p] == NONE {
                    continue;
                }
                let rate = if range > 1e-6 {
                    (rest_dist[p] - start) / range
                } else {
                    0.0
                };
                targets.push((p as u32, t.scale_curve_by_bone_length_rate.eval(rate)));
            }
        }
        out.push(CompiledSync {
            bone,
            rest: rest_models[bone].translation,
            settings: e.clone(),
            targets,
        });
    }
    Ok(out)
}

/// Moves the chains' `targets` by every sync bone's share of its source's movement
/// (KawaiiPhysics' `ApplySyncBones`), keeping each target at its animated length from its
/// parent's target. `animated`: the targets as gathered (their lengths); `pos`: the
/// simulated points (the distance attenuation reads them); `models`: the animated pose.
pub(crate) fn apply(
    syncs: &[CompiledSync],
    parent: &[u32],
    models: &[crate::math::Transform],
    animated: &[Vec3],
    pos: &[Vec3],
    targets: &mut [Vec3],
) {
    for sync in syncs {
        let s = &sync.settings;
        let source = models[sync.bone].translation;
        let mut delta = source - sync.rest;
        if !s.scale_curve_by_delta_distance.keys.is_empty() {
            delta *= s.scale_curve_by_delta_distance.eval(delta.length());
        }
        delta *= s.global_scale;
        let delta = Vec3::new(
            if s.apply_direction_x.keeps(delta.x) {
                delta.x
            } else {
                0.0
            },
            if s.apply_direction_y.keeps(delta.y) {
                delta.y
            } else {
                0.0
            },
            if s.apply_direction_z.keeps(delta.z) {
                delta.z
            } else {
                0.0
            },
        );
        if delta == Vec3::ZERO {
            continue;
        }
        for &(p, scale) in &sync.targets {
            let p = p as usize;
            let alpha = if s.enable_distance_attenuation {
                attenuation(s, (source - pos[p]).length())
            } else {
                1.0
            };
            let moved = targets[p] + delta * alpha * scale;
            let pp = parent[p] as usize;
            let length = (animated[p] - animated[pp]).length();
            targets[p] = (moved - targets[pp]).normalize_or_zero() * length + targets[pp];
        }
    }
}

/// KawaiiPhysics' distance attenuation: 1 within the inner radius, falling linearly to
/// `1 − max_attenuation_rate` at the outer.
fn attenuation(s: &SyncBoneSettings, distance: f32) -> f32 {
    let (inner, outer) = (
        s.attenuation_inner_radius,
        s.attenuation_outer_radius.max(s.attenuation_inner_radius),
    );
    let amount = if distance <= inner {
        0.0
    } else if distance >= outer {
        s.max_attenuation_rate
    } else {
        let span = outer - inner;
        let t = if span > 1e-6 {
            (distance - inner) / span
        } else {
            1.0
        };
        t * s.max_attenuation_rate
    };
    (1.0 - amount).max(0.0)
}
