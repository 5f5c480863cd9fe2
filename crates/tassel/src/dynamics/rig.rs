//! The rig file: chains and colliders attached to a skeleton by bone names (TOML; see
//! docs/rig.md).

use crate::collide::{PlacedCollider, Shape};
use crate::dynamics::chain::{
    BoneConstraintOptions, BoneConstraintSettings, ChainSettings, Compliance, SyncBoneSettings,
};
use crate::dynamics::cloth::ClothSettings;
use crate::dynamics::rope::RopeSettings;
use crate::dynamics::spring::SpringSettings;
use crate::dynamics::vrm::{VrmOptions, VrmStepping};
use crate::error::{Error, Result};
use crate::math::Transform;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// A collider attached to a bone.
// No `deny_unknown_fields` here: serde does not support it together with the flattened
// shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColliderSettings {
    /// Name, referenced by chains' `colliders` lists.
    pub name: String,
    /// The bone it follows (its animated pose).
    pub bone: String,
    /// Offset from the bone in the bone's space, metres.
    #[serde(default)]
    pub offset: Vec3,
    /// Rotation relative to the bone, `[x, y, z, w]`.
    #[serde(default = "identity")]
    pub rotation: Quat,
    /// The shape.
    #[serde(flatten)]
    pub shape: Shape,
    /// Also make this collider's twin on the other side of the character, mirrored across
    /// the plane normal to this axis of the character (`"x"`: left ↔ right for a glTF
    /// character; KawaiiPhysics 1.21's mirrored limits): named `<name>_mirror`, on the
    /// bone `mirror_bone` names, or else the bone whose name swaps a side marker
    /// (`_L`/`_R`, `.L`/`.R`, `L_`/`R_`, `Left`/`Right`, in either case).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mirror: Option<MirrorAxis>,
    /// The twin's bone, when the side markers do not find it.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub mirror_bone: String,
}

/// The axis a mirrored collider is reflected along (the plane of symmetry is normal to it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MirrorAxis {
    /// The character's X axis (left and right of a glTF character facing +Z).
    X,
    /// Its Y axis.
    Y,
    /// Its Z axis.
    Z,
}

impl MirrorAxis {
    /// `v` reflected across the plane normal to this axis (`FAnimationRuntime::MirrorVector`).
    pub fn vector(self, v: Vec3) -> Vec3 {
        match self {
            MirrorAxis::X => Vec3::new(-v.x, v.y, v.z),
            MirrorAxis::Y => Vec3::new(v.x, -v.y, v.z),
            MirrorAxis::Z => Vec3::new(v.x, v.y, -v.z),
        }
    }

    /// The rotation `q` seen in the mirror (`M·R·M`: `FAnimationRuntime::MirrorQuat`).
    pub fn rotation(self, q: Quat) -> Quat {
        match self {
            MirrorAxis::X => Quat::from_xyzw(q.x, -q.y, -q.z, q.w),
            MirrorAxis::Y => Quat::from_xyzw(-q.x, q.y, -q.z, q.w),
            MirrorAxis::Z => Quat::from_xyzw(-q.x, -q.y, q.z, q.w),
        }
    }
}

/// Side markers a mirrored collider's bone name may carry, swapped to find its twin:
/// suffixes, prefixes, then anywhere in the name.
const SIDE_SUFFIXES: [(&str, &str); 4] = [("_L", "_R"), ("_l", "_r"), (".L", ".R"), (".l", ".r")];
const SIDE_PREFIXES: [(&str, &str); 2] = [("L_", "R_"), ("l_", "r_")];
const SIDE_WORDS: [(&str, &str); 3] = [("Left", "Right"), ("left", "right"), ("LEFT", "RIGHT")];

/// The bone on the other side of `name`, by its side marker, if the skeleton has it.
fn mirror_bone_of(skeleton: &Skeleton, name: &str) -> Option<usize> {
    let swaps = |a: &str, b: &str| {
        [
            (a.to_string(), b.to_string()),
            (b.to_string(), a.to_string()),
        ]
    };
    let mut candidates = Vec::new();
    for (a, b) in SIDE_SUFFIXES.iter().flat_map(|(a, b)| swaps(a, b)) {
        if let Some(stem) = name.strip_suffix(a.as_str()) {
            candidates.push(format!("{stem}{b}"));
        }
    }
    for (a, b) in SIDE_PREFIXES.iter().flat_map(|(a, b)| swaps(a, b)) {
        if let Some(rest) = name.strip_prefix(a.as_str()) {
            candidates.push(format!("{b}{rest}"));
        }
    }
    for (a, b) in SIDE_WORDS.iter().flat_map(|(a, b)| swaps(a, b)) {
        if name.contains(a.as_str()) {
            candidates.push(name.replacen(a.as_str(), &b, 1));
        }
    }
    candidates
        .iter()
        .filter(|c| c.as_str() != name)
        .find_map(|c| skeleton.find(c))
}

fn identity() -> Quat {
    Quat::IDENTITY
}

/// A rig collider with its bone resolved: what every solver places each frame.
#[derive(Debug, Clone)]
pub(crate) struct CompiledCollider {
    pub bone: usize,
    pub offset: Transform,
    pub shape: Shape,
}

impl CompiledCollider {
    /// Every collider of `rig` (bone names must have been checked).
    pub fn compile_all(skeleton: &Skeleton, rig: &RigSettings) -> Vec<Self> {
        rig.colliders
            .iter()
            .map(|c| CompiledCollider {
                bone: skeleton.find(&c.bone).unwrap_or(0),
                offset: Transform::from_translation_rotation(c.offset, c.rotation.normalize()),
                shape: c.shape,
            })
            .collect()
    }

    /// Where it is for the model pose `models`: in model space without `frame`, in the
    /// space `frame` maps model space to (the character's transform: world) with it.
    /// Scale is ignored.
    pub fn place(&self, models: &[Transform], frame: Option<&Transform>) -> PlacedCollider {
        let b = &models[self.bone];
        let bone = Transform::from_translation_rotation(b.translation, b.rotation);
        self.place_on(&match frame {
            Some(f) => *f * bone,
            None => bone,
        })
    }

    /// Where it is when its bone is at `bone` (scale is ignored).
    pub fn place_on(&self, bone: &Transform) -> PlacedCollider {
        let t = *bone * self.offset;
        PlacedCollider {
            shape: self.shape,
            transform: Transform::from_translation_rotation(t.translation, t.rotation),
        }
    }
}

/// Everything a rig file holds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSettings {
    /// The compliance of `[[bone_constraint]]` entries without their own (KawaiiPhysics'
    /// `BoneConstraintGlobalComplianceType`; default `"leather"`).
    #[serde(default)]
    pub bone_constraint_global_compliance_type: Compliance,
    /// Bone-constraint solver passes before each step's collision pass (KawaiiPhysics
    /// 1.21's `BoneConstraintIterationCountBeforeCollision`; default 0, as 1.20 runs).
    #[serde(default)]
    pub bone_constraint_iteration_count_before_collision: u32,
    /// Bone-constraint solver passes after each step's collision pass
    /// (`BoneConstraintIterationCountAfterCollision`; default 1).
    #[serde(default = "one")]
    pub bone_constraint_iteration_count_after_collision: u32,
    /// A constraint whose two bones both end in a dummy tip (`dummy_bone_length`) also
    /// joins the tips (`bAutoAddChildDummyBoneConstraint`; default true).
    #[serde(default = "yes")]
    pub auto_add_child_dummy_bone_constraint: bool,
    /// Bridge points on each bone constraint, 0..=10 (KawaiiPhysics 1.21's
    /// `BoneConstraintSubdivisionCount`; default 0): collision sensors between the two
    /// points that close the gap a leg passes through between a skirt's columns.
    #[serde(default, skip_serializing_if = "is_zero_u32")]
    pub bone_constraint_subdivision_count: u32,
    /// How much of a bridge point's push reaches the constraint's two points, 0..=2
    /// (`BoneConstraintSubdivisionFeedbackScale`; default 1).
    #[serde(default = "one_f32", skip_serializing_if = "is_one_f32")]
    pub bone_constraint_subdivision_feedback_scale: f32,
    /// How `fixed` mode steps the model's VRM spring bones (`[vrm]`: `step_rate`,
    /// `max_steps_per_frame`).
    #[serde(default, skip_serializing_if = "VrmStepping::is_default")]
    pub vrm: VrmStepping,
    /// Bone chains (`[[chain]]` tables).
    #[serde(default, rename = "chain")]
    pub chains: Vec<ChainSettings>,
    /// Colliders (`[[collider]]` tables).
    #[serde(default, rename = "collider")]
    pub colliders: Vec<ColliderSettings>,
    /// Spring bones (`[[spring]]` tables).
    #[serde(default, rename = "spring")]
    pub springs: Vec<SpringSettings>,
    /// Bone cloths (`[[cloth]]` tables).
    #[serde(default, rename = "cloth")]
    pub cloths: Vec<ClothSettings>,
    /// Ropes on bones driven by the particle world (`[[rope]]` tables).
    #[serde(default, rename = "rope")]
    pub ropes: Vec<RopeSettings>,
    /// Distance constraints between simulated chain bones (`[[bone_constraint]]` tables;
    /// KawaiiPhysics' bone constraints).
    #[serde(
        default,
        rename = "bone_constraint",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub bone_constraints: Vec<BoneConstraintSettings>,
    /// Chain bones whose targets follow a source bone's movement (`[[sync_bone]]` tables;
    /// KawaiiPhysics' sync bones).
    #[serde(default, rename = "sync_bone", skip_serializing_if = "Vec::is_empty")]
    pub sync_bones: Vec<SyncBoneSettings>,
    /// Forces on chain bones (`[[external_force]]` tables; KawaiiPhysics' external forces:
    /// `basic`, `curve` and `gravity`).
    #[serde(
        default,
        rename = "external_force",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub external_forces: Vec<crate::dynamics::chain::ExternalForceSettings>,
    /// Named groups of this rig's colliders that other characters may collide with
    /// (`[[collider_group]]`: `name`, `colliders`; see
    /// [`crate::CharacterSim::shared_colliders`]).
    #[serde(
        default,
        rename = "collider_group",
        skip_serializing_if = "Vec::is_empty"
    )]
    pub collider_groups: Vec<ColliderGroupSettings>,
}

/// A named group of a rig's colliders (`[[collider_group]]`), shared with other characters
/// by name (KawaiiPhysics' shared collision source tag).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColliderGroupSettings {
    /// The group's name.
    pub name: String,
    /// The colliders in it, by name.
    pub colliders: Vec<String>,
}

fn one() -> u32 {
    1
}

fn one_f32() -> f32 {
    1.0
}

fn is_one_f32(v: &f32) -> bool {
    *v == 1.0
}

fn is_zero_u32(n: &u32) -> bool {
    *n == 0
}

fn yes() -> bool {
    true
}

impl Default for RigSettings {
    fn default() -> Self {
        Self {
            bone_constraint_global_compliance_type: Compliance::default(),
            bone_constraint_iteration_count_before_collision: 0,
            bone_constraint_iteration_count_after_collision: 1,
            auto_add_child_dummy_bone_constraint: true,
            bone_constraint_subdivision_count: 0,
            bone_constraint_subdivision_feedback_scale: 1.0,
            vrm: VrmStepping::default(),
            chains: Vec::new(),
            colliders: Vec::new(),
            springs: Vec::new(),
            cloths: Vec::new(),
            ropes: Vec::new(),
            bone_constraints: Vec::new(),
            sync_bones: Vec::new(),
            external_forces: Vec::new(),
            collider_groups: Vec::new(),
        }
    }
}

impl RigSettings {
    /// Parses a rig from TOML text and checks every parameter.
    pub fn from_toml_str(text: &str) -> Result<Self> {
        let mut rig: RigSettings =
            toml::from_str(text).map_err(|e| Error::RigParse(e.to_string()))?;
        rig.spcr_defaults(text)?;
        rig.validate()?;
        Ok(rig)
    }

    /// Gives each `[[cloth]]` table that says `mode = "spcr"` SPCRJointDynamics' default
    /// for the keys it leaves out where that differs from Tassel's
    /// ([`crate::dynamics::cloth::ClothSettings::spcr`]).
    fn spcr_defaults(&mut self, text: &str) -> Result<()> {
        use crate::dynamics::cloth::ClothMode;
        if self.cloths.iter().all(|c| c.mode != ClothMode::Spcr) {
            return Ok(());
        }
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| Error::RigParse(e.to_string()))?;
        let given = table.get("cloth").and_then(|c| c.as_array());
        for (i, cloth) in self.cloths.iter_mut().enumerate() {
            if cloth.mode != ClothMode::Spcr {
                continue;
            }
            let keys = given.and_then(|g| g.get(i)).and_then(|t| t.as_table());
            for key in crate::dynamics::cloth::settings::SPCR_DEFAULTED_KEYS {
                if !keys.is_some_and(|t| t.contains_key(key)) {
                    cloth.set_spcr_default(key);
                }
            }
        }
        Ok(())
    }

    /// The rig as TOML text.
    pub fn to_toml_string(&self) -> Result<String> {
        toml::to_string(self).map_err(|e| Error::RigParse(e.to_string()))
    }

    /// The rig with the twin of each collider that asks for one (`mirror`): KawaiiPhysics
    /// 1.21's mirrored limits (`KawaiiPhysicsMirror::AppendMirroredLimits`). The twin
    /// rides the mirror bone with the offset and rotation KawaiiPhysics gives it, from the
    /// two bones' rest rotations in the character's space (`Rs`, `Rt`) and the mirror `M`:
    /// `offset = Rt⁻¹ · M(Rs · offset)`, `rotation = Rt⁻¹ · M(Rs · rotation) · M(Rs)⁻¹ ·
    /// Rt`. So on a symmetric rest pose the twin's centre is the source's mirrored. Every
    /// chain, cloth and rope that names the source also collides with the twin. Borrowed
    /// when no collider mirrors. An error names a collider whose twin bone cannot be
    /// found, is its own bone, or whose twin's name is taken.
    pub fn mirrored(&self, skeleton: &Skeleton) -> Result<std::borrow::Cow<'_, RigSettings>> {
        use std::borrow::Cow;
        if self.colliders.iter().all(|c| c.mirror.is_none()) {
            return Ok(Cow::Borrowed(self));
        }
        // Rest rotations in the character's space (parents come before children).
        let mut rest_cs: Vec<Quat> = Vec::with_capacity(skeleton.len());
        for j in 0..skeleton.len() {
            let local = skeleton.rest()[j].rotation;
            let q = match skeleton.parent(j) {
                Some(p) => rest_cs[p] * local,
                None => local,
            };
            rest_cs.push(q.normalize());
        }
        let mut out = self.clone();
        let mut twins: Vec<(String, String)> = Vec::new();
        for c in &self.colliders {
            let Some(axis) = c.mirror else { continue };
            let what = format!("collider '{}' mirror", c.name);
            let source = skeleton.find(&c.bone).ok_or_else(|| Error::MissingBone {
                context: format!("collider '{}' bone", c.name),
                name: c.bone.clone(),
            })?;
            let target = if c.mirror_bone.is_empty() {
                mirror_bone_of(skeleton, &c.bone).ok_or_else(|| {
                    Error::InvalidParameter(format!(
                        "{what}: no bone mirrors '{}' (no _L/_R, .L/.R, L_/R_ or Left/Right \
                         twin in the skeleton); name it with mirror_bone",
                        c.bone
                    ))
                })?
            } else {
                skeleton
                    .find(&c.mirror_bone)
                    .ok_or_else(|| Error::MissingBone {
                        context: format!("collider '{}' mirror_bone", c.name),
                        name: c.mirror_bone.clone(),
                    })?
            };
            if target == source {
                return Err(Error::InvalidParameter(format!(
                    "{what}: bone '{}' is its own mirror",
                    c.bone
                )));
            }
            let (rs, rt) = (rest_cs[source], rest_cs[target]);
            let offset = rt.inverse() * axis.vector(rs * c.offset);
            let rotation = (rt.inverse()
                * axis.rotation(rs * c.rotation.normalize())
                * axis.rotation(rs).inverse()
                * rt)
                .normalize();
            let name = format!("{}_mirror", c.name);
            twins.push((c.name.clone(), name.clone()));
            out.colliders.push(ColliderSettings {
                name,
                bone: skeleton.name(target).to_string(),
                offset,
                rotation,
                shape: c.shape,
                mirror: None,
                mirror_bone: String::new(),
            });
        }
        let add_twins = |names: &mut Vec<String>| {
            for (source, twin) in &twins {
                if names.contains(source) && !names.contains(twin) {
                    names.push(twin.clone());
                }
            }
        };
        for c in &mut out.chains {
            add_twins(&mut c.colliders);
        }
        for c in &mut out.cloths {
            add_twins(&mut c.colliders);
        }
        for r in &mut out.ropes {
            add_twins(&mut r.colliders);
        }
        // The twins' names must be free (checked with everything else).
        out.validate()?;
        Ok(Cow::Owned(out))
    }

    /// Checks parameter ranges and internal references (not bone names: see
    /// [`RigSettings::validate_for`]).
    pub fn validate(&self) -> Result<()> {
        use crate::limits::{MAX_COLLIDERS, MAX_SOLVERS};
        for (what, n) in [
            ("chains", self.chains.len()),
            ("springs", self.springs.len()),
            ("cloths", self.cloths.len()),
            ("ropes", self.ropes.len()),
        ] {
            if n > MAX_SOLVERS {
                return Err(Error::InvalidParameter(format!(
                    "the rig defines {n} {what}, more than the limit of {MAX_SOLVERS}"
                )));
            }
        }
        if self.colliders.len() > MAX_COLLIDERS {
            return Err(Error::InvalidParameter(format!(
                "the rig defines {} colliders, more than the limit of {MAX_COLLIDERS}",
                self.colliders.len()
            )));
        }
        self.vrm.apply(VrmOptions::default()).validate()?;
        // Name sets, not scans: every check below is linear in the rig's size.
        let mut colliders = std::collections::HashSet::with_capacity(self.colliders.len());
        for col in &self.colliders {
            let what = format!("collider '{}'", col.name);
            col.shape.validate(&what)?;
            if !col.offset.is_finite() || !col.rotation.is_finite() || col.rotation.length() < 1e-6
            {
                return Err(Error::InvalidParameter(format!(
                    "{what}: offset or rotation is not finite"
                )));
            }
            if !colliders.insert(col.name.as_str()) {
                return Err(Error::InvalidParameter(format!(
                    "two colliders are named '{}'",
                    col.name
                )));
            }
        }
        let known = |who: &str, names: &[String]| -> Result<()> {
            match names.iter().find(|n| !colliders.contains(n.as_str())) {
                Some(name) => Err(Error::InvalidParameter(format!(
                    "{who} names collider '{name}', which the rig does not define"
                ))),
                None => Ok(()),
            }
        };
        for c in &self.chains {
            c.validate()?;
            known(&format!("chain '{}'", c.name), &c.colliders)?;
        }
        let mut groups = std::collections::HashSet::with_capacity(self.collider_groups.len());
        for g in &self.collider_groups {
            if g.name.is_empty() {
                return Err(Error::InvalidParameter(
                    "a [[collider_group]] has no name".into(),
                ));
            }
            if !groups.insert(g.name.as_str()) {
                return Err(Error::InvalidParameter(format!(
                    "two collider groups are named '{}'",
                    g.name
                )));
            }
            known(&format!("collider group '{}'", g.name), &g.colliders)?;
        }
        for s in &self.springs {
            s.validate()?;
        }
        self.bone_constraint_global_compliance_type
            .validate("bone_constraint_global_compliance_type")?;
        for (key, n) in [
            (
                "bone_constraint_iteration_count_before_collision",
                self.bone_constraint_iteration_count_before_collision,
            ),
            (
                "bone_constraint_iteration_count_after_collision",
                self.bone_constraint_iteration_count_after_collision,
            ),
        ] {
            if n > crate::limits::MAX_ITERATIONS {
                return Err(Error::InvalidParameter(format!(
                    "{key} = {n} is more than the limit of {}",
                    crate::limits::MAX_ITERATIONS
                )));
            }
        }
        if self.bone_constraint_subdivision_count > 10 {
            return Err(Error::InvalidParameter(format!(
                "bone_constraint_subdivision_count = {} must be 0..=10",
                self.bone_constraint_subdivision_count
            )));
        }
        let scale = self.bone_constraint_subdivision_feedback_scale;
        if !(0.0..=2.0).contains(&scale) {
            return Err(Error::InvalidParameter(format!(
                "bone_constraint_subdivision_feedback_scale = {scale} must be 0..=2"
            )));
        }
        for (i, c) in self.bone_constraints.iter().enumerate() {
            c.validate(i + 1)?;
        }
        for (i, s) in self.sync_bones.iter().enumerate() {
            s.validate(i + 1)?;
        }
        for f in &self.external_forces {
            f.validate()?;
        }
        for r in &self.ropes {
            r.validate()?;
            known(&format!("rope '{}'", r.name), &r.colliders)?;
        }
        let mut cloths = std::collections::HashSet::with_capacity(self.cloths.len());
        for c in &self.cloths {
            c.validate()?;
            if !cloths.insert(c.name.as_str()) {
                return Err(Error::InvalidParameter(format!(
                    "two cloths are named '{}'",
                    c.name
                )));
            }
            known(&format!("cloth '{}'", c.name), &c.colliders)?;
        }
        Ok(())
    }

    /// The rig-wide bone-constraint settings.
    pub fn bone_constraint_options(&self) -> BoneConstraintOptions {
        BoneConstraintOptions {
            global_compliance: self.bone_constraint_global_compliance_type,
            iterations_before_collision: self.bone_constraint_iteration_count_before_collision,
            iterations_after_collision: self.bone_constraint_iteration_count_after_collision,
            auto_add_child_dummy: self.auto_add_child_dummy_bone_constraint,
            subdivision_count: self.bone_constraint_subdivision_count,
            feedback_scale: self.bone_constraint_subdivision_feedback_scale,
        }
    }

    /// Indices into `colliders` of the named colliders, in the order named (all of them
    /// when `names` is empty); unknown names are skipped ([`RigSettings::validate`]
    /// reports them). One map per call, so a rig's compile stays linear in its size.
    pub(crate) fn collider_indices(&self, names: &[String]) -> Vec<usize> {
        if names.is_empty() {
            return (0..self.colliders.len()).collect();
        }
        let index: std::collections::HashMap<&str, usize> = self
            .colliders
            .iter()
            .enumerate()
            .map(|(i, c)| (c.name.as_str(), i))
            .collect();
        names
            .iter()
            .filter_map(|n| index.get(n.as_str()).copied())
            .collect()
    }

    /// [`RigSettings::validate`] plus every bone name checked against `skeleton`.
    pub fn validate_for(&self, skeleton: &Skeleton) -> Result<()> {
        self.validate()?;
        let need = |context: String, name: &str| {
            skeleton
                .find(name)
                .map(|_| ())
                .ok_or_else(|| Error::MissingBone {
                    context,
                    name: name.to_string(),
                })
        };
        for c in &self.chains {
            need(format!("chain '{}' root", c.name), &c.root)?;
            for e in &c.exclude {
                need(format!("chain '{}' exclude", c.name), e)?;
            }
            if !c.simulation_base_bone.is_empty() {
                let what = format!("chain '{}' simulation_base_bone", c.name);
                need(what.clone(), &c.simulation_base_bone)?;
                let (base, root) = (
                    skeleton.find(&c.simulation_base_bone),
                    skeleton.find(&c.root),
                );
                if let (Some(base), Some(root)) = (base, root) {
                    if base == root || !skeleton.is_descendant_of(root, base) {
                        return Err(Error::InvalidParameter(format!(
                            "{what} '{}' is not an ancestor of its root '{}'",
                            c.simulation_base_bone, c.root
                        )));
                    }
                }
            }
        }
        for col in &self.colliders {
            need(format!("collider '{}' bone", col.name), &col.bone)?;
        }
        for s in &self.springs {
            need(format!("spring '{}' bone", s.name), &s.bone)?;
        }
        for r in &self.ropes {
            need(format!("rope '{}' root", r.name), &r.root)?;
            need(format!("rope '{}' end", r.name), &r.end)?;
        }
        for c in &self.cloths {
            for [root, end] in &c.chains {
                need(format!("cloth '{}' chain root", c.name), root)?;
                need(format!("cloth '{}' chain end", c.name), end)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RIG: &str = r#"
[[chain]]
name = "tail"
root = "tail_0"
damping = 0.2
curves.stiffness = [[0.0, 1.0], [1.0, 0.5]]

[[collider]]
name = "hips"
bone = "hips"
shape = "capsule"
radius = 0.1
length = 0.2
offset = [0.0, 0.05, 0.0]
"#;

    #[test]
    fn parses_with_defaults() {
        let rig = RigSettings::from_toml_str(RIG).unwrap();
        assert_eq!(rig.chains[0].damping, 0.2);
        assert_eq!(rig.chains[0].stiffness, ChainSettings::default().stiffness);
        assert_eq!(rig.chains[0].curves.stiffness.eval(0.5), 0.75);
        assert_eq!(
            rig.colliders[0].shape,
            Shape::Capsule {
                radius: 0.1,
                length: 0.2
            }
        );
        let again = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
        assert_eq!(again, rig);
    }

    #[test]
    fn rejects_bad_values_by_name() {
        let neg = RIG.replace("radius = 0.1", "radius = -0.1");
        let e = RigSettings::from_toml_str(&neg).unwrap_err().to_string();
        assert!(e.contains("hips") && e.contains("radius"), "{e}");
        let nan = RIG.replace("damping = 0.2", "damping = nan");
        let e = RigSettings::from_toml_str(&nan).unwrap_err().to_string();
        assert!(e.contains("damping"), "{e}");
        let typo = RIG.replace("damping = 0.2", "dampnig = 0.2");
        assert!(matches!(
            RigSettings::from_toml_str(&typo),
            Err(Error::RigParse(_))
        ));
    }

    #[test]
    fn parses_a_cloth_table() {
        let text = r#"
[[cloth]]
name = "skirt"
chains = [["s0_0", "s0_3"], ["s1_0", "s1_3"], ["s2_0", "s2_3"]]
loop_chains = true
virtual_bone_length = 0.05
surface_collision = "push"
stretch.shear = [[0.0, 0.5], [1.0, 0.2]]
constraints.bending_horizontal = true
wind.acceleration = [1.0, 0.0, 0.0]
"#;
        let rig = RigSettings::from_toml_str(text).unwrap();
        let c = &rig.cloths[0];
        assert!(c.loop_chains && c.constraints.bending_horizontal);
        assert_eq!(c.chains[2], ["s2_0".to_string(), "s2_3".to_string()]);
        assert_eq!(c.stretch.shear.eval(0.5), 0.35);
        assert_eq!(c.iterations, ClothSettings::default().iterations);
        assert_eq!(
            c.surface_collision,
            crate::dynamics::cloth::SurfaceCollision::Push
        );
        let again = RigSettings::from_toml_str(&rig.to_toml_string().unwrap()).unwrap();
        assert_eq!(again, rig);
        let bad = text.replace("virtual_bone_length = 0.05", "virtual_bone_length = -1.0");
        let e = RigSettings::from_toml_str(&bad).unwrap_err().to_string();
        assert!(
            e.contains("skirt") && e.contains("virtual_bone_length"),
            "{e}"
        );
    }
}
