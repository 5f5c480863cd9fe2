//! Compiling `[[cloth]]` settings against a skeleton: points, constraints, quads.

use super::settings::{ClothSettings, StrengthCurves};
use crate::dynamics::{CompiledCollider, RigSettings};
use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use std::ops::Range;

/// The constraint families.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConstraintKind {
    /// Along a chain, neighbours.
    StructuralVertical,
    /// Across chains, neighbours.
    StructuralHorizontal,
    /// Quad diagonals.
    Shear,
    /// Along a chain, two apart.
    BendingVertical,
    /// Across chains, two apart.
    BendingHorizontal,
}

/// One distance constraint between two points of a cloth.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClothConstraint {
    /// First point.
    pub a: u32,
    /// Second point.
    pub b: u32,
    /// Rest length (animated rest pose), metres.
    pub length: f32,
    /// Strength against shrinking, 0..=1.
    pub shrink: f32,
    /// Strength against stretching, 0..=1.
    pub stretch: f32,
    /// Its family.
    pub kind: ConstraintKind,
}

#[derive(Debug, Clone)]
pub(crate) struct CompiledCloth {
    pub settings: ClothSettings,
    /// Points of this cloth (global point indices).
    pub points: Range<usize>,
    /// Per chain, its points in order from the root.
    pub chains: Vec<Range<usize>>,
    pub constraints: Range<usize>,
    /// Quads `[p00, p10, p11, p01]` (chain i at k, chain i+1 at k, … at k+1).
    pub quads: Vec<[u32; 4]>,
    pub colliders: Vec<usize>,
    /// The structural constraints (global indices), in order: the segments the segment
    /// collision keeps out of the colliders.
    pub structural: Vec<u32>,
    /// The quads' triangles in the order the surface collision takes them: per quad
    /// `[p00, p10, p11]` then `[p00, p11, p01]`.
    pub triangles: Vec<[u32; 3]>,
    /// The constraints by dependency level ([`dependency_levels`]), as the relaxation
    /// reads them.
    pub relaxed: Vec<Relaxed>,
    /// In the `spcr` mode: SPCR's constraints, quads and per-point values.
    pub spcr: Option<super::spcr::SpcrRig>,
}

/// A constraint as its relaxation reads it: ends, rest length, strengths, and the
/// weights of its ends (1 movable, 0 fixed) and the share of the correction each movable
/// end takes, which depend on the rig only.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Relaxed {
    pub a: u32,
    pub b: u32,
    pub length: f32,
    pub shrink: f32,
    pub stretch: f32,
    pub wa: f32,
    pub wb: f32,
    pub share: f32,
}

impl Relaxed {
    /// Constraint `c` of a rig whose fixed points are `fixed`.
    #[inline(always)]
    pub(crate) fn of(c: &ClothConstraint, fixed: &[bool]) -> Relaxed {
        let wa = if fixed[c.a as usize] { 0.0 } else { 1.0 };
        let wb = if fixed[c.b as usize] { 0.0 } else { 1.0 };
        // The correction is shared among the movable ends (the rig has no constraint
        // between two fixed points): divided by 1 or 2, written as a product by 1 or 0.5,
        // which is exact either way (the same bits), without a division.
        let share = if wa + wb > 1.5 { 0.5 } else { 1.0 };
        Relaxed {
            a: c.a,
            b: c.b,
            length: c.length,
            shrink: c.shrink,
            stretch: c.stretch,
            wa,
            wb,
            share,
        }
    }
}

/// `constraints` (global indices `first..`) reordered by dependency level, stably: a
/// constraint's level is one more than the highest level of the constraints before it
/// (in the rig's order) that share a point with it. Relaxed in this order, every
/// constraint meets its two points as the rig's order leaves them — each constraint
/// before it on one of its points has a lower level, each after it a higher one — so the
/// results are the same bits, while the constraints of one level (no two share a point)
/// are independent and the processor overlaps their latencies.
pub(crate) fn dependency_levels(constraints: &[ClothConstraint], first: usize) -> Vec<u32> {
    let mut level_of_point: std::collections::HashMap<u32, u32> = Default::default();
    let mut levelled: Vec<(u32, u32)> = constraints
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let level = 1 + level_of_point
                .get(&c.a)
                .copied()
                .unwrap_or(0)
                .max(level_of_point.get(&c.b).copied().unwrap_or(0));
            level_of_point.insert(c.a, level);
            level_of_point.insert(c.b, level);
            (level, (first + i) as u32)
        })
        .collect();
    levelled.sort_by_key(|&(level, _)| level);
    levelled.into_iter().map(|(_, i)| i).collect()
}

/// Every `[[cloth]]` of a rig compiled for one skeleton. Immutable: share it between the
/// characters that use the same skeleton and rig.
#[derive(Debug, Clone, Default)]
pub struct ClothRig {
    pub(crate) cloths: Vec<CompiledCloth>,
    pub(crate) colliders: Vec<CompiledCollider>,
    // Per point (structure of arrays).
    /// Joint of the point, or `None` for a virtual tip (then `tip_of` is its bone).
    pub(crate) joint: Vec<Option<usize>>,
    /// For a virtual tip: the end bone and the one before it (direction), and its length.
    pub(crate) tip_of: Vec<Option<(usize, usize, f32)>>,
    pub(crate) fixed: Vec<bool>,
    pub(crate) resistance: Vec<f32>,
    pub(crate) hardness: Vec<f32>,
    pub(crate) gravity_scale: Vec<f32>,
    pub(crate) drag: Vec<f32>,
    pub(crate) lift: Vec<f32>,
    pub(crate) radius: Vec<f32>,
    pub(crate) friction: Vec<f32>,
    pub(crate) constraints: Vec<ClothConstraint>,
}

impl ClothRig {
    /// Compiles every cloth of `rig` for `skeleton`. Errors name the cloth and the bone.
    pub fn new(skeleton: &Skeleton, rig: &RigSettings) -> Result<Self> {
        rig.validate_for(skeleton)?;
        let rig = &*rig.mirrored(skeleton)?;
        let mut out = ClothRig::default();
        if rig.cloths.is_empty() {
            return Ok(out);
        }
        out.colliders = CompiledCollider::compile_all(skeleton, rig);
        let rest = crate::pose::Pose::rest(skeleton);
        let mut owner: Vec<Option<usize>> = vec![None; skeleton.len()];
        for (ci, s) in rig.cloths.iter().enumerate() {
            let first = out.joint.len();
            let mut chains = Vec::with_capacity(s.chains.len());
            for [root_name, end_name] in &s.chains {
                let missing = |n: &str| Error::MissingBone {
                    context: format!("cloth '{}' chain", s.name),
                    name: n.to_string(),
                };
                let root = skeleton.find(root_name).ok_or_else(|| missing(root_name))?;
                let end = skeleton.find(end_name).ok_or_else(|| missing(end_name))?;
                let mut bones = vec![end];
                let mut j = end;
                while j != root {
                    j = skeleton.parent(j).ok_or_else(|| {
                        Error::InvalidParameter(format!(
                            "cloth '{}': bone '{end_name}' is not below '{root_name}'",
                            s.name
                        ))
                    })?;
                    bones.push(j);
                }
                bones.reverse();
                if bones.len() < 2 && s.virtual_bone_length <= 0.0 {
                    return Err(Error::InvalidParameter(format!(
                        "cloth '{}': chain '{root_name}'..'{end_name}' has a single bone and no virtual tip",
                        s.name
                    )));
                }
                let start = out.joint.len();
                for &b in &bones {
                    if let Some(other) = owner[b] {
                        return Err(Error::InvalidParameter(format!(
                            "cloth '{}': bone '{}' is already simulated by cloth '{}'",
                            s.name,
                            skeleton.name(b),
                            rig.cloths[other].name
                        )));
                    }
                    owner[b] = Some(ci);
                    out.joint.push(Some(b));
                    out.tip_of.push(None);
                }
                if s.virtual_bone_length > 0.0 {
                    let last = bones[bones.len() - 1];
                    let before = if bones.len() > 1 {
                        bones[bones.len() - 2]
                    } else {
                        skeleton.parent(last).unwrap_or(last)
                    };
                    out.joint.push(None);
                    out.tip_of.push(Some((last, before, s.virtual_bone_length)));
                }
                chains.push(start..out.joint.len());
            }
            // Per-point parameters over the normalised chain position.
            for ch in &chains {
                let n = ch.len();
                for k in 0..n {
                    let x = if n > 1 {
                        k as f32 / (n - 1) as f32
                    } else {
                        0.0
                    };
                    let c = &s.curves;
                    out.fixed.push(k as u32 <= s.fixed_point_index);
                    out.resistance
                        .push((s.resistance * c.resistance.eval(x)).clamp(0.0, 1.0));
                    out.hardness
                        .push((s.hardness * c.hardness.eval(x)).clamp(0.0, 1.0));
                    out.gravity_scale
                        .push(s.gravity_scale * c.gravity_scale.eval(x));
                    out.drag.push((s.drag * c.drag.eval(x)).max(0.0));
                    out.lift.push((s.lift * c.lift.eval(x)).max(0.0));
                    out.radius.push((s.radius * c.radius.eval(x)).max(0.0));
                    out.friction
                        .push((s.friction * c.friction.eval(x)).clamp(0.0, 1.0));
                }
            }
            // Rest positions for the rest lengths.
            let pos: Vec<glam::Vec3> = (first..out.joint.len())
                .map(|p| match (out.joint[p], out.tip_of[p]) {
                    (Some(j), _) => rest.models[j].translation,
                    (None, Some((last, before, len))) => {
                        let a = rest.models[before].translation;
                        let b = rest.models[last].translation;
                        b + crate::math::normalize_or(b - a, glam::Vec3::NEG_Y) * len
                    }
                    _ => glam::Vec3::ZERO,
                })
                .collect();
            let cstart = out.constraints.len();
            let mut quads = Vec::new();
            let count = chains.len();
            let pairs = |gap: usize| -> Vec<(usize, usize)> {
                let mut v: Vec<(usize, usize)> = (0..count.saturating_sub(gap))
                    .map(|i| (i, i + gap))
                    .collect();
                if s.loop_chains && count > 2 * gap {
                    v.extend((count - gap..count).map(|i| (i, (i + gap) % count)));
                }
                v
            };
            let mut add = |a: usize,
                           b: usize,
                           x: f32,
                           kind: ConstraintKind,
                           curves: (&StrengthCurves, &StrengthCurves)| {
                let pick = |c: &StrengthCurves| match kind {
                    ConstraintKind::StructuralVertical => c.structural_vertical.eval(x),
                    ConstraintKind::StructuralHorizontal => c.structural_horizontal.eval(x),
                    ConstraintKind::Shear => c.shear.eval(x),
                    ConstraintKind::BendingVertical => c.bending_vertical.eval(x),
                    ConstraintKind::BendingHorizontal => c.bending_horizontal.eval(x),
                };
                if out.fixed[a] && out.fixed[b] {
                    return;
                }
                out.constraints.push(ClothConstraint {
                    a: a as u32,
                    b: b as u32,
                    length: (pos[a - first] - pos[b - first]).length(),
                    shrink: pick(curves.0).clamp(0.0, 1.0),
                    stretch: pick(curves.1).clamp(0.0, 1.0),
                    kind,
                });
            };
            let sc = (&s.shrink, &s.stretch);
            let sw = &s.constraints;
            let xn = |ch: &Range<usize>, k: usize| {
                if ch.len() > 1 {
                    k as f32 / (ch.len() - 1) as f32
                } else {
                    0.0
                }
            };
            for ch in &chains {
                for k in 0..ch.len() {
                    let x = xn(ch, k);
                    if sw.structural_vertical && k + 1 < ch.len() {
                        add(
                            ch.start + k,
                            ch.start + k + 1,
                            x,
                            ConstraintKind::StructuralVertical,
                            sc,
                        );
                    }
                    if sw.bending_vertical && k + 2 < ch.len() {
                        add(
                            ch.start + k,
                            ch.start + k + 2,
                            x,
                            ConstraintKind::BendingVertical,
                            sc,
                        );
                    }
                }
            }
            for (i, j) in pairs(1) {
                let (a, b) = (&chains[i], &chains[j]);
                for k in 0..a.len().min(b.len()) {
                    let x = xn(a, k);
                    if sw.structural_horizontal {
                        add(
                            a.start + k,
                            b.start + k,
                            x,
                            ConstraintKind::StructuralHorizontal,
                            sc,
                        );
                    }
                    if k + 1 < a.len().min(b.len()) {
                        if sw.shear {
                            add(a.start + k, b.start + k + 1, x, ConstraintKind::Shear, sc);
                            add(b.start + k, a.start + k + 1, x, ConstraintKind::Shear, sc);
                        }
                        quads.push([
                            (a.start + k) as u32,
                            (b.start + k) as u32,
                            (b.start + k + 1) as u32,
                            (a.start + k + 1) as u32,
                        ]);
                    }
                }
            }
            if sw.bending_horizontal {
                for (i, j) in pairs(2) {
                    let (a, b) = (&chains[i], &chains[j]);
                    for k in 0..a.len().min(b.len()) {
                        add(
                            a.start + k,
                            b.start + k,
                            xn(a, k),
                            ConstraintKind::BendingHorizontal,
                            sc,
                        );
                    }
                }
            }
            let colliders = rig.collider_indices(&s.colliders);
            let structural = (cstart..out.constraints.len())
                .filter(|&i| {
                    matches!(
                        out.constraints[i].kind,
                        ConstraintKind::StructuralVertical | ConstraintKind::StructuralHorizontal
                    )
                })
                .map(|i| i as u32)
                .collect();
            let triangles = quads
                .iter()
                .flat_map(|&[q00, q10, q11, q01]| [[q00, q10, q11], [q00, q11, q01]])
                .collect();
            let schedule = dependency_levels(&out.constraints[cstart..], cstart);
            let relaxed = schedule
                .iter()
                .map(|&i| Relaxed::of(&out.constraints[i as usize], &out.fixed))
                .collect();
            let spcr = (s.mode == super::settings::ClothMode::Spcr).then(|| {
                let tips: Vec<bool> = out.joint.iter().map(|j| j.is_none()).collect();
                super::spcr::SpcrRig::build(s, &chains, &tips, &out.fixed)
            });
            out.cloths.push(CompiledCloth {
                spcr,
                settings: s.clone(),
                points: first..out.joint.len(),
                chains,
                constraints: cstart..out.constraints.len(),
                quads,
                colliders,
                structural,
                triangles,
                relaxed,
            });
        }
        Ok(out)
    }

    /// True without cloths.
    pub fn is_empty(&self) -> bool {
        self.cloths.is_empty()
    }

    /// Number of cloths.
    pub fn cloth_count(&self) -> usize {
        self.cloths.len()
    }

    /// Number of points of every cloth (bones and virtual tips).
    pub fn point_count(&self) -> usize {
        self.joint.len()
    }

    /// The joints a cloth moves (its free points that are bones).
    pub fn simulated_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.joint
            .iter()
            .zip(&self.fixed)
            .filter_map(|(j, f)| if *f { None } else { *j })
    }

    /// The joints a cloth turns toward its simulated points: every bone followed in its
    /// chain by a free point, pinned bones (the first row) included. A superset of
    /// [`simulated_joints`](Self::simulated_joints) by those pinned bones.
    pub fn turned_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.cloths.iter().flat_map(move |cloth| {
            cloth.chains.iter().flat_map(move |ch| {
                (ch.start..ch.end.saturating_sub(1))
                    .filter(move |&p| !self.fixed[p + 1])
                    .filter_map(move |p| self.joint[p])
            })
        })
    }

    /// Point ranges of cloth `i`'s chains, in order.
    pub fn chains(&self, i: usize) -> &[Range<usize>] {
        &self.cloths[i].chains
    }

    /// The constraints of cloth `i`.
    pub fn constraints(&self, i: usize) -> &[ClothConstraint] {
        &self.constraints[self.cloths[i].constraints.clone()]
    }

    /// The quads of cloth `i`, `[p00, p10, p11, p01]`.
    pub fn quads(&self, i: usize) -> &[[u32; 4]] {
        &self.cloths[i].quads
    }

    /// The settings of cloth `i`.
    pub fn settings(&self, i: usize) -> &ClothSettings {
        &self.cloths[i].settings
    }

    /// Rig collider indices used by cloth `i`.
    pub fn cloth_colliders(&self, i: usize) -> &[usize] {
        &self.cloths[i].colliders
    }

    /// Collision radius of point `p`.
    pub fn point_radius(&self, p: usize) -> f32 {
        self.radius[p]
    }

    /// The joint point `p` moves (`None` for a virtual tip).
    pub fn joint(&self, p: usize) -> Option<usize> {
        self.joint[p]
    }

    /// Whether point `p` follows the animation.
    pub fn is_fixed(&self, p: usize) -> bool {
        self.fixed[p]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The schedule of the built-in skirt (every constraint family, a closed ring):
    /// a permutation of the cloth's constraints in which every pair that shares a point
    /// keeps the rig's order (what makes the results the same bits), and which really
    /// brings independent constraints together (levels of several).
    #[test]
    fn the_dependency_schedule_keeps_the_order_of_every_pair_that_shares_a_point() {
        let c = crate::builtin::character();
        let rig = ClothRig::new(&c.skeleton, &c.rig).unwrap();
        let cloth = &rig.cloths[0];
        let range = cloth.constraints.clone();
        let schedule = dependency_levels(&rig.constraints[range.clone()], range.start);
        // The cloth relaxes its constraints in that order.
        let ends = |c: &Relaxed| (c.a, c.b);
        let scheduled_ends: Vec<_> = schedule
            .iter()
            .map(|&i| (rig.constraints[i as usize].a, rig.constraints[i as usize].b))
            .collect();
        assert_eq!(
            cloth.relaxed.iter().map(ends).collect::<Vec<_>>(),
            scheduled_ends
        );
        let mut at = vec![usize::MAX; rig.constraints.len()];
        for (k, &i) in schedule.iter().enumerate() {
            assert!(range.contains(&(i as usize)), "{i} is not the cloth's");
            assert_eq!(at[i as usize], usize::MAX, "{i} twice");
            at[i as usize] = k;
        }
        assert_eq!(schedule.len(), range.len());
        let mut pairs = 0;
        for i in range.clone() {
            for k in i + 1..range.end {
                let (x, y) = (&rig.constraints[i], &rig.constraints[k]);
                if [x.a, x.b].iter().any(|p| *p == y.a || *p == y.b) {
                    pairs += 1;
                    assert!(
                        at[i] < at[k],
                        "constraints {i} and {k} share a point: order kept"
                    );
                }
            }
        }
        assert!(pairs > 100, "{pairs}");
        // Runs of the schedule in which no two constraints share a point: how far the
        // schedule groups independent work (the rig's order has runs of 1–2 only).
        let runs = |order: &[u32]| {
            let mut runs = 1;
            let mut seen: Vec<u32> = Vec::new();
            for &i in order {
                let c = &rig.constraints[i as usize];
                if seen.contains(&c.a) || seen.contains(&c.b) {
                    runs += 1;
                    seen.clear();
                }
                seen.extend([c.a, c.b]);
            }
            runs
        };
        let rig_order: Vec<u32> = range.map(|i| i as u32).collect();
        let (scheduled, ordered) = (runs(&schedule), runs(&rig_order));
        println!(
            "skirt: {} constraints in {scheduled} independent runs (rig order: {ordered})",
            rig_order.len()
        );
        assert!(
            scheduled * 2 < ordered,
            "{scheduled} independent runs scheduled vs {ordered} in the rig's order"
        );
    }
}
