//! Bone constraints after KawaiiPhysics 1.14–1.21 (`FModifyBoneConstraint`): distance
//! constraints between pairs of simulated points, also across chains (neighbouring skirt
//! chains, a cape's columns), solved by XPBD with KawaiiPhysics' compliance presets.
//!
//! Chains joined by constraints form a *group*, stepped together in KawaiiPhysics 1.20's
//! phase order (every point integrated, constraints, collisions, constraints, then limits and
//! bone lengths); chains in no group keep the per-point order of 1.10. See docs/chains.md.

use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use glam::Vec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::ops::Range;

/// KawaiiPhysics' compliance presets (`EXPBDComplianceType`), in m²/N: how much a
/// constraint gives under load. Smaller is stiffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CompliancePreset {
    /// 0.04·10⁻⁹.
    Concrete,
    /// 0.16·10⁻⁹.
    Wood,
    /// 1.0·10⁻⁸ (KawaiiPhysics' default, as its source writes it: 0.000000001).
    #[default]
    Leather,
    /// 0.2·10⁻⁷.
    Tendon,
    /// 1.0·10⁻⁶.
    Rubber,
    /// 0.2·10⁻³.
    Muscle,
    /// 1.0·10⁻³.
    Fat,
}

impl CompliancePreset {
    /// Every preset, stiffest first.
    pub const ALL: [CompliancePreset; 7] = [
        CompliancePreset::Concrete,
        CompliancePreset::Wood,
        CompliancePreset::Leather,
        CompliancePreset::Tendon,
        CompliancePreset::Rubber,
        CompliancePreset::Muscle,
        CompliancePreset::Fat,
    ];

    /// The compliance KawaiiPhysics uses for the preset (its `XPBDComplianceValues`
    /// table, the same numbers: the solve divides by the squared step, so the value is
    /// unit-free in effect and holds in metres as in centimetres).
    pub fn value(self) -> f32 {
        match self {
            CompliancePreset::Concrete => 0.000_000_000_04,
            CompliancePreset::Wood => 0.000_000_000_16,
            CompliancePreset::Leather => 0.000_000_001,
            CompliancePreset::Tendon => 0.000_000_002,
            CompliancePreset::Rubber => 0.000_000_1,
            CompliancePreset::Muscle => 0.000_02,
            CompliancePreset::Fat => 0.000_1,
        }
    }

    /// The preset's name in rig files.
    pub fn name(self) -> &'static str {
        match self {
            CompliancePreset::Concrete => "concrete",
            CompliancePreset::Wood => "wood",
            CompliancePreset::Leather => "leather",
            CompliancePreset::Tendon => "tendon",
            CompliancePreset::Rubber => "rubber",
            CompliancePreset::Muscle => "muscle",
            CompliancePreset::Fat => "fat",
        }
    }
}

/// A bone constraint's compliance: a KawaiiPhysics preset by name, or a number (m²/N,
/// ≥ 0; 0 is rigid). In a rig file: `compliance = "rubber"` or `compliance = 2e-6`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Compliance {
    /// One of KawaiiPhysics' presets.
    Preset(CompliancePreset),
    /// A value of one's own.
    Value(f32),
}

impl Default for Compliance {
    fn default() -> Self {
        Compliance::Preset(CompliancePreset::Leather)
    }
}

impl Compliance {
    /// The number the solver uses.
    pub fn value(self) -> f32 {
        match self {
            Compliance::Preset(p) => p.value(),
            Compliance::Value(v) => v,
        }
    }

    pub(crate) fn validate(self, what: &str) -> Result<()> {
        let v = self.value();
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(Error::InvalidParameter(format!(
                "{what}: compliance must be a finite number ≥ 0 or a preset name, got {v}"
            )))
        }
    }
}

impl Serialize for Compliance {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Compliance::Preset(p) => s.serialize_str(p.name()),
            Compliance::Value(v) => s.serialize_f32(*v),
        }
    }
}

impl<'de> Deserialize<'de> for Compliance {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Compliance;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a compliance: concrete, wood, leather, tendon, rubber, muscle, fat or a number",
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<Compliance, E> {
                CompliancePreset::ALL
                    .into_iter()
                    .find(|p| p.name() == v)
                    .map(Compliance::Preset)
                    .ok_or_else(|| {
                        E::custom(format!(
                            "unknown compliance preset '{v}' (concrete, wood, leather, tendon, \
                             rubber, muscle or fat, or a number)"
                        ))
                    })
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Compliance, E> {
                Ok(Compliance::Value(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Compliance, E> {
                Ok(Compliance::Value(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Compliance, E> {
                Ok(Compliance::Value(v as f32))
            }
        }
        d.deserialize_any(V)
    }
}

/// One `[[bone_constraint]]` entry: a pair of simulated bones by name, or pairs generated
/// by two name patterns (regular expressions matched against whole bone names in skeleton
/// order; the k-th match of `bone1_pattern` pairs with the k-th of `bone2_pattern`, as
/// KawaiiPhysics' data asset pairs its `RegexPatternList`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BoneConstraintSettings {
    /// The first bone (simulated by a chain).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub bone1: String,
    /// The second bone (simulated by a chain).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub bone2: String,
    /// Instead of `bone1`: a regular expression over bone names.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub bone1_pattern: String,
    /// Instead of `bone2`: a regular expression over bone names.
    #[serde(skip_serializing_if = "String::is_empty")]
    pub bone2_pattern: String,
    /// This entry's compliance; none: the rig's `bone_constraint_global_compliance_type`
    /// (KawaiiPhysics' `bOverrideCompliance` off).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compliance: Option<Compliance>,
    /// Put no bridge points on this pair (`bone_constraint_subdivision_count`; its dummy
    /// tips' pair too): KawaiiPhysics 1.21's `bExcludeFromSubdivision`, for structural or
    /// diagonal constraints.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub exclude_from_subdivision: bool,
}

impl BoneConstraintSettings {
    /// A constraint between two bones by name, with the rig's compliance.
    pub fn between(bone1: &str, bone2: &str) -> Self {
        Self {
            bone1: bone1.into(),
            bone2: bone2.into(),
            ..Default::default()
        }
    }

    /// Checks the entry's form (`n`: its 1-based place in the rig file).
    pub(crate) fn validate(&self, n: usize) -> Result<()> {
        let what = self.describe(n);
        for (name, pattern, key) in [
            (&self.bone1, &self.bone1_pattern, "bone1"),
            (&self.bone2, &self.bone2_pattern, "bone2"),
        ] {
            match (name.is_empty(), pattern.is_empty()) {
                (true, true) => {
                    return Err(Error::InvalidParameter(format!(
                        "{what}: give {key} or {key}_pattern"
                    )))
                }
                (false, false) => {
                    return Err(Error::InvalidParameter(format!(
                        "{what}: give {key} or {key}_pattern, not both"
                    )))
                }
                _ => {}
            }
        }
        if self.bone1_pattern.is_empty() != self.bone2_pattern.is_empty() {
            return Err(Error::InvalidParameter(format!(
                "{what}: patterns pair with patterns: give bone1_pattern and bone2_pattern, \
                 or bone1 and bone2"
            )));
        }
        if !self.bone1.is_empty() && self.bone1 == self.bone2 {
            return Err(Error::InvalidParameter(format!(
                "{what}: a bone cannot be constrained to itself"
            )));
        }
        if let Some(c) = self.compliance {
            c.validate(&what)?;
        }
        Ok(())
    }

    fn describe(&self, n: usize) -> String {
        if self.bone1.is_empty() {
            format!(
                "bone_constraint #{n} ('{}' – '{}')",
                self.bone1_pattern, self.bone2_pattern
            )
        } else {
            format!("bone_constraint #{n} ('{}' – '{}')", self.bone1, self.bone2)
        }
    }

    /// The bone pairs of the entry on `skeleton`.
    fn pairs(&self, n: usize, skeleton: &Skeleton) -> Result<Vec<(usize, usize)>> {
        let what = self.describe(n);
        if self.bone1_pattern.is_empty() {
            let find = |name: &str| {
                skeleton.find(name).ok_or_else(|| Error::MissingBone {
                    context: what.clone(),
                    name: name.to_string(),
                })
            };
            return Ok(vec![(find(&self.bone1)?, find(&self.bone2)?)]);
        }
        let matches = |pattern: &str, key: &str| -> Result<Vec<usize>> {
            let re = regex_lite::Regex::new(&format!("^(?:{pattern})$")).map_err(|e| {
                Error::InvalidParameter(format!(
                    "{what}: {key}_pattern is not a regular expression: {e}"
                ))
            })?;
            let found: Vec<usize> = (0..skeleton.len())
                .filter(|&j| re.is_match(skeleton.name(j)))
                .collect();
            if found.is_empty() {
                return Err(Error::InvalidParameter(format!(
                    "{what}: {key}_pattern matches no bone"
                )));
            }
            Ok(found)
        };
        let a = matches(&self.bone1_pattern, "bone1")?;
        let b = matches(&self.bone2_pattern, "bone2")?;
        if a.len() != b.len() {
            return Err(Error::InvalidParameter(format!(
                "{what}: bone1_pattern matches {} bones and bone2_pattern {}; they pair in order, \
                 so the counts must agree",
                a.len(),
                b.len()
            )));
        }
        Ok(a.into_iter().zip(b).collect())
    }
}

/// The rig-wide settings of bone constraints (KawaiiPhysics' node properties of the same
/// names), top-level keys of the rig file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneConstraintOptions {
    /// The compliance of entries without their own.
    pub global_compliance: Compliance,
    /// Solver passes before the collision pass of each step (KawaiiPhysics from 1.21; 0
    /// is 1.20's update).
    pub iterations_before_collision: u32,
    /// Solver passes after the collision pass of each step (1.20: one).
    pub iterations_after_collision: u32,
    /// A constraint whose two bones both end in a dummy tip also joins the tips.
    pub auto_add_child_dummy: bool,
    /// Bridge points on each constraint (0..=10; KawaiiPhysics 1.21's
    /// `BoneConstraintSubdivisionCount`).
    pub subdivision_count: u32,
    /// How much of a bridge point's push reaches the constraint's two points (0..=2;
    /// `BoneConstraintSubdivisionFeedbackScale`).
    pub feedback_scale: f32,
}

/// A compiled constraint between points `a` and `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CompiledConstraint {
    pub a: u32,
    pub b: u32,
    /// Rest distance: the points' distance in the skeleton's rest pose.
    pub rest: f32,
    pub compliance: f32,
    /// Bridge points may be put on it (not `exclude_from_subdivision`).
    pub bridged: bool,
}

/// A bridge point on a bone constraint (KawaiiPhysics 1.21's bridge dummy): a collision
/// sensor at `alpha` of the way from point `a` to point `b`, placed there each step, whose
/// push by the colliders moves `a` and `b` by their shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Bridge {
    pub a: u32,
    pub b: u32,
    pub alpha: f32,
    /// The mean of the two points' radii.
    pub radius: f32,
}

/// Chains joined by bone constraints: stepped together.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ChainGroup {
    /// Chain indices, ascending.
    pub chains: Vec<usize>,
    /// The group's constraints in `ChainRig::constraints`, in file order, then the dummy
    /// tips' (as KawaiiPhysics appends them).
    pub constraints: Range<usize>,
    /// The group's bridge points in `Constraints::bridges`.
    pub bridges: Range<usize>,
}

/// Everything the chain rig keeps of its bone constraints.
#[derive(Debug, Clone, Default)]
pub(crate) struct Constraints {
    pub list: Vec<CompiledConstraint>,
    pub groups: Vec<ChainGroup>,
    /// Per chain: its group, or `u32::MAX`.
    pub group_of: Vec<u32>,
    pub before: u32,
    pub after: u32,
    /// Bridge points, group by group, and how much of their push reaches their ends.
    pub bridges: Vec<Bridge>,
    pub feedback_scale: f32,
    /// Every rig collider (bridge points collide with all of them).
    pub all_colliders: Vec<usize>,
}

/// What [`compile`] needs of the chain points.
pub(crate) struct PointTable<'a> {
    pub joint: &'a [u16],
    pub parent: &'a [u32],
    /// Virtual tips' lengths (0: not a tip).
    pub dummy_length: &'a [f32],
    /// Per point between bones (`bone_subdivision_count`): its place on its segment (0:
    /// not such a point).
    pub inter_alpha: &'a [f32],
    pub chain_of: &'a [u16],
    /// Rest-pose position of every point (virtual tips included).
    pub rest: &'a [Vec3],
    /// Collision radius of every point.
    pub radius: &'a [f32],
}

/// Resolves `entries` on `skeleton` against the compiled chain points.
pub(crate) fn compile(
    skeleton: &Skeleton,
    entries: &[BoneConstraintSettings],
    options: &BoneConstraintOptions,
    points: &PointTable,
    chains: &[super::compile::CompiledChain],
) -> Result<Constraints> {
    use super::compile::{NONE, VIRTUAL};
    let mut out = Constraints {
        group_of: vec![u32::MAX; chains.len()],
        before: options.iterations_before_collision,
        after: options.iterations_after_collision,
        feedback_scale: options.feedback_scale,
        ..Default::default()
    };
    if entries.is_empty() {
        return Ok(out);
    }
    let mut point_of = vec![NONE; skeleton.len()];
    for (p, &j) in points.joint.iter().enumerate() {
        if j != VIRTUAL {
            point_of[j as usize] = p as u32;
        }
    }
    let constraint = |a: usize, b: usize, compliance: f32, bridged: bool| CompiledConstraint {
        a: a as u32,
        b: b as u32,
        rest: (points.rest[b] - points.rest[a]).length(),
        compliance,
        bridged,
    };
    // A bone's virtual tip, when it hangs from the bone itself (KawaiiPhysics 1.21 looks
    // among the bone's children: a tip behind points between bones is joined by the
    // pairs across the columns below instead).
    let dummy_child = |p: usize| {
        let chain = &chains[points.chain_of[p] as usize];
        chain.points.clone().find(|&c| {
            points.parent[c] == p as u32
                && points.joint[c] == VIRTUAL
                && points.inter_alpha[c] == 0.0
                && points.dummy_length[c] > 0.0
        })
    };
    // The points between bones below bone point `p`, in order from it, and the virtual
    // tip after them when they split the chain's last segment (KawaiiPhysics 1.21's
    // `CollectInterBoneDummies`).
    let inter_below = |p: usize| -> Vec<usize> {
        let chain = &chains[points.chain_of[p] as usize];
        let mut out = Vec::new();
        let mut at = p;
        while let Some(n) = chain
            .points
            .clone()
            .find(|&c| points.parent[c] == at as u32 && points.inter_alpha[c] > 0.0)
        {
            out.push(n);
            at = n;
        }
        if !out.is_empty() {
            if let Some(tip) = chain.points.clone().find(|&c| {
                points.parent[c] == at as u32
                    && points.joint[c] == VIRTUAL
                    && points.inter_alpha[c] == 0.0
                    && points.dummy_length[c] > 0.0
            }) {
                out.push(tip);
            }
        }
        out
    };
    let mut list = Vec::new();
    let mut dummies = Vec::new();
    for (i, e) in entries.iter().enumerate() {
        e.validate(i + 1)?;
        let what = e.describe(i + 1);
        let compliance = e.compliance.unwrap_or(options.global_compliance).value();
        for (ja, jb) in e.pairs(i + 1, skeleton)? {
            let simulated = |j: usize| {
                let p = point_of[j];
                if p == NONE || points.parent[p as usize] == NONE {
                    Err(Error::InvalidParameter(format!(
                        "{what}: bone '{}' is not simulated by any chain (a chain's root is \
                         animated, not simulated)",
                        skeleton.name(j)
                    )))
                } else {
                    Ok(p as usize)
                }
            };
            let (a, b) = (simulated(ja)?, simulated(jb)?);
            if a == b {
                return Err(Error::InvalidParameter(format!(
                    "{what}: bone '{}' is paired with itself",
                    skeleton.name(ja)
                )));
            }
            let bridged = !e.exclude_from_subdivision;
            list.push(constraint(a, b, compliance, bridged));
            if options.auto_add_child_dummy {
                if let (Some(da), Some(db)) = (dummy_child(a), dummy_child(b)) {
                    dummies.push(constraint(da, db, compliance, bridged));
                }
                // Across subdivided columns (KawaiiPhysics 1.21's `CollectInterBoneDummies`):
                // the points between bones below the two bones joined pair by pair (as many
                // pairs as the shorter side has), at their rest distance, with the global
                // compliance (1.21 gives them no other); the tips behind split last
                // segments are the last pair.
                let global = options.global_compliance.value();
                let (ia, ib) = (inter_below(a), inter_below(b));
                for (&pa, &pb) in ia.iter().zip(&ib) {
                    dummies.push(constraint(pa, pb, global, bridged));
                }
            }
            if list.len() + dummies.len() > crate::limits::MAX_BONE_CONSTRAINTS {
                return Err(Error::InvalidParameter(format!(
                    "{what}: the rig's bone constraints number more than {} (the limit)",
                    crate::limits::MAX_BONE_CONSTRAINTS
                )));
            }
        }
    }
    list.extend(dummies);
    let solves = list
        .len()
        .saturating_mul((out.before as usize).saturating_add(out.after as usize));
    if solves > crate::limits::MAX_CONSTRAINT_SOLVES {
        return Err(Error::InvalidParameter(format!(
            "bone constraints: {} constraints × {} iterations is more than {} solves per step \
             (the limit)",
            list.len(),
            out.before as usize + out.after as usize,
            crate::limits::MAX_CONSTRAINT_SOLVES
        )));
    }
    // Groups: chains joined by any constraint (union–find over chains).
    let mut root: Vec<usize> = (0..chains.len()).collect();
    fn find(root: &mut [usize], mut c: usize) -> usize {
        while root[c] != c {
            root[c] = root[root[c]];
            c = root[c];
        }
        c
    }
    for c in &list {
        let ca = find(&mut root, points.chain_of[c.a as usize] as usize);
        let cb = find(&mut root, points.chain_of[c.b as usize] as usize);
        root[ca.max(cb)] = ca.min(cb);
    }
    let mut constrained = vec![false; chains.len()];
    for c in &list {
        constrained[points.chain_of[c.a as usize] as usize] = true;
        constrained[points.chain_of[c.b as usize] as usize] = true;
    }
    for ci in 0..chains.len() {
        if !constrained[ci] {
            continue;
        }
        let r = find(&mut root, ci);
        if out.group_of[r] == u32::MAX {
            out.group_of[r] = out.groups.len() as u32;
            out.groups.push(ChainGroup {
                chains: Vec::new(),
                constraints: 0..0,
                bridges: 0..0,
            });
        }
        let g = out.group_of[r];
        out.group_of[ci] = g;
        out.groups[g as usize].chains.push(ci);
    }
    // The constraints group by group, each group's in file order.
    for (g, group) in out.groups.iter_mut().enumerate() {
        let start = out.list.len();
        out.list.extend(
            list.iter()
                .copied()
                .filter(|c| out.group_of[points.chain_of[c.a as usize] as usize] == g as u32),
        );
        group.constraints = start..out.list.len();
        check_group(chains, group)?;
        // Bridge points (KawaiiPhysics 1.21's `InsertBridgeDummiesForConstraints`): on
        // every constraint not excluded, unless its two points' spheres already overlap at
        // rest (KINDA_SMALL_NUMBER, 1e-4 cm, in metres).
        let first = out.bridges.len();
        for c in &out.list[group.constraints.clone()] {
            let (a, b) = (c.a as usize, c.b as usize);
            let (ra, rb) = (points.radius[a], points.radius[b]);
            if !c.bridged || c.rest <= (ra + rb).max(1e-6) {
                continue;
            }
            let n = options.subdivision_count.min(10) as usize;
            for k in 0..n {
                out.bridges.push(Bridge {
                    a: c.a,
                    b: c.b,
                    alpha: (k + 1) as f32 / (n + 1) as f32,
                    radius: 0.5 * (ra + rb),
                });
            }
        }
        group.bridges = first..out.bridges.len();
    }
    Ok(out)
}

/// The chains of a group step together: their clocks must agree.
fn check_group(chains: &[super::compile::CompiledChain], group: &ChainGroup) -> Result<()> {
    let first = &chains[group.chains[0]].settings;
    for &ci in &group.chains[1..] {
        let s = &chains[ci].settings;
        let differs = if s.mode != first.mode {
            Some("mode")
        } else if s.target_framerate != first.target_framerate {
            Some("target_framerate")
        } else if s.max_steps_per_frame != first.max_steps_per_frame {
            Some("max_steps_per_frame")
        } else if s.max_delta_time != first.max_delta_time {
            Some("max_delta_time")
        } else if s.warmup_steps != first.warmup_steps {
            Some("warmup_steps")
        } else {
            None
        };
        if let Some(key) = differs {
            return Err(Error::InvalidParameter(format!(
                "bone constraints join chains '{}' and '{}', which step together: their {key} \
                 must agree",
                first.name, s.name
            )));
        }
    }
    Ok(())
}

/// `iterations` XPBD passes over `constraints` for a step of `dt` seconds
/// (KawaiiPhysics' `AdjustByBoneConstraints`, with the Lagrange multipliers `lambda` reset
/// first as its update does before each batch of passes). Unit masses. Each correction
/// moves the points by `part` of it: 1 in a step; fixed mode's output step (a part of a
/// step, `StepInput::part`) moves them that part of the way, so that a part near 0
/// leaves the last step's points where they are.
pub(crate) fn solve(
    constraints: &[CompiledConstraint],
    lambda: &mut [f32],
    pos: &mut [Vec3],
    dt: f32,
    iterations: u32,
    part: f32,
) {
    if iterations == 0 {
        return;
    }
    lambda.fill(0.0);
    for _ in 0..iterations {
        for (c, l) in constraints.iter().zip(lambda.iter_mut()) {
            let (a, b) = (c.a as usize, c.b as usize);
            let d = pos[b] - pos[a];
            let len = d.length();
            if len <= 0.0 || len.is_nan() {
                continue;
            }
            let alpha = c.compliance / (dt * dt);
            let dl = (len - c.rest - alpha * *l) / (2.0 + alpha);
            let delta = d / len * dl * part;
            pos[a] += delta;
            pos[b] -= delta;
            *l += dl;
        }
    }
}
