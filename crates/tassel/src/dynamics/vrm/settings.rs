//! VRM spring-bone settings: plain data, as a VRM file defines them, with joints given as
//! skeleton indices (the glTF importer maps node indices to joints).

use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::constraint::NodeConstraint;
use super::limit::VrmLimit;

/// All spring bones of one model (`VRMC_springBone` 1.0 or VRM 0.x `secondaryAnimation`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VrmSpringBones {
    /// Collider shapes, each attached to a joint.
    pub colliders: Vec<VrmCollider>,
    /// Named lists of colliders that springs refer to.
    pub collider_groups: Vec<VrmColliderGroup>,
    /// The springs.
    pub springs: Vec<VrmSpring>,
    /// The file's `VRMC_node_constraint` constraints, evaluated on the animated pose
    /// before the springs.
    #[serde(default)]
    pub node_constraints: Vec<NodeConstraint>,
}

/// A collider attached to a joint.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VrmCollider {
    /// The joint (node) the collider moves with.
    pub joint: usize,
    /// Its shape in the joint's local space.
    pub shape: VrmShape,
}

/// A collider shape in the local space of its joint. Offsets and tails are local points
/// (scaled with the joint); radii are world metres (as three-vrm reads them).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum VrmShape {
    /// A sphere; `inside` keeps tails inside it (extended collider).
    Sphere {
        /// Centre, local.
        offset: Vec3,
        /// Radius, metres (≥ 0).
        radius: f32,
        /// Keep tails inside instead of outside.
        inside: bool,
    },
    /// A capsule from `offset` to `tail`; `inside` keeps tails inside it.
    Capsule {
        /// Head end, local.
        offset: Vec3,
        /// Tail end, local.
        tail: Vec3,
        /// Radius, metres (≥ 0).
        radius: f32,
        /// Keep tails inside instead of outside.
        inside: bool,
    },
    /// An infinite plane through `offset`; tails stay on the side `normal` points to.
    Plane {
        /// A point of the plane, local.
        offset: Vec3,
        /// Normal, local (non-zero; normalised when placed).
        normal: Vec3,
    },
}

/// A named list of collider indices.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VrmColliderGroup {
    /// Name from the file (may be empty).
    pub name: String,
    /// Indices into [`VrmSpringBones::colliders`].
    pub colliders: Vec<usize>,
}

/// One spring: a list of joints that swing, with the colliders they hit.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VrmSpring {
    /// Name from the file (VRM 0.x: the bone group's comment).
    pub name: String,
    /// The simulated joints (heads); each has a tail.
    pub joints: Vec<VrmJoint>,
    /// Indices into [`VrmSpringBones::collider_groups`].
    pub collider_groups: Vec<usize>,
    /// Tails are kept in this joint's space instead of world space (the spec's `center`).
    pub center: Option<usize>,
}

/// Where a simulated joint's tail is.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum VrmTail {
    /// A descendant joint (VRM 1.0: the next joint of the spring; VRM 0.x: the first child).
    Joint(usize),
    /// A point in the joint's local space (VRM 0.x leaf bones: 7 cm along the bone).
    Local(Vec3),
}

/// One simulated joint (the spec's head of a joint pair) and its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct VrmJoint {
    /// The joint that turns.
    pub joint: usize,
    /// Its tail.
    pub tail: VrmTail,
    /// Radius of the tail's sphere against colliders, metres (≥ 0).
    pub hit_radius: f32,
    /// Pull back to the rest direction, per second (≥ 0).
    pub stiffness: f32,
    /// Gravity strength, metres per second of tail motion (≥ 0).
    pub gravity_power: f32,
    /// Gravity direction, world space (used as given, like the reference implementations).
    pub gravity_dir: Vec3,
    /// Share of the last frame's motion lost per frame, 0..=1.
    pub drag_force: f32,
    /// How far the joint may swing (`VRMC_springBone_limit`); `None`: anywhere.
    #[serde(default)]
    pub limit: Option<VrmLimit>,
}

impl Default for VrmJoint {
    /// The `VRMC_springBone` 1.0 schema defaults.
    fn default() -> Self {
        Self {
            joint: 0,
            tail: VrmTail::Local(Vec3::new(0.0, 0.07, 0.0)),
            hit_radius: 0.0,
            stiffness: 1.0,
            gravity_power: 0.0,
            gravity_dir: Vec3::new(0.0, -1.0, 0.0),
            drag_force: 0.5,
            limit: None,
        }
    }
}

impl VrmSpringBones {
    /// True when there is no spring.
    pub fn is_empty(&self) -> bool {
        self.springs.iter().all(|s| s.joints.is_empty()) && self.node_constraints.is_empty()
    }

    /// Every simulated joint, spring by spring.
    pub fn simulated_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.springs
            .iter()
            .flat_map(|s| s.joints.iter().map(|j| j.joint))
    }

    /// Checks every reference and parameter against `skeleton`. Errors name the spring,
    /// the joint and the problem: a joint out of range, a tail that is not below its joint,
    /// a joint in two springs (or twice in one), a negative or non-finite radius, a drag
    /// outside 0..=1, NaN in a gravity direction, a missing collider or group, a centre
    /// out of range, a zero plane normal.
    pub fn validate_for(&self, skeleton: &Skeleton) -> Result<()> {
        let n = skeleton.len();
        let bad = |m: String| Err(Error::InvalidParameter(m));
        use crate::limits::{MAX_COLLIDERS, MAX_SOLVERS};
        if self.colliders.len() > MAX_COLLIDERS {
            return bad(format!(
                "VRM spring bones: {} colliders, more than the limit of {MAX_COLLIDERS}",
                self.colliders.len()
            ));
        }
        if self.springs.len() > MAX_SOLVERS || self.collider_groups.len() > MAX_SOLVERS {
            return bad(format!(
                "VRM spring bones: {} springs and {} collider groups; the limit is {MAX_SOLVERS} each",
                self.springs.len(),
                self.collider_groups.len()
            ));
        }
        let name = |j: usize| {
            if j < n {
                format!("'{}'", skeleton.name(j))
            } else {
                format!("#{j}")
            }
        };
        for (ci, c) in self.colliders.iter().enumerate() {
            if c.joint >= n {
                return bad(format!(
                    "VRM collider {ci}: joint {} does not exist ({n} joints)",
                    c.joint
                ));
            }
            let what = format!("VRM collider {ci} on {}", name(c.joint));
            let point = |p: &str, v: Vec3| {
                if v.is_finite() {
                    Ok(())
                } else {
                    Err(Error::NonFinite(format!("{what}: {p} {v}")))
                }
            };
            match c.shape {
                VrmShape::Sphere { offset, radius, .. } => {
                    point("offset", offset)?;
                    if !(radius.is_finite() && radius >= 0.0) {
                        return bad(format!("{what}: radius {radius} must be finite and ≥ 0"));
                    }
                }
                VrmShape::Capsule {
                    offset,
                    tail,
                    radius,
                    ..
                } => {
                    point("offset", offset)?;
                    point("tail", tail)?;
                    if !(radius.is_finite() && radius >= 0.0) {
                        return bad(format!("{what}: radius {radius} must be finite and ≥ 0"));
                    }
                }
                VrmShape::Plane { offset, normal } => {
                    point("offset", offset)?;
                    point("normal", normal)?;
                    if normal.length_squared() < 1e-12 {
                        return bad(format!("{what}: the plane normal is zero"));
                    }
                }
            }
        }
        for (gi, g) in self.collider_groups.iter().enumerate() {
            if let Some(&c) = g.colliders.iter().find(|&&c| c >= self.colliders.len()) {
                return bad(format!(
                    "VRM collider group {gi} ('{}'): collider {c} does not exist ({} colliders)",
                    g.name,
                    self.colliders.len()
                ));
            }
        }
        let mut owner: Vec<Option<usize>> = vec![None; n];
        let mut pairs = 0usize;
        for (si, s) in self.springs.iter().enumerate() {
            let sname = format!("VRM spring {si} ('{}')", s.name);
            if let Some(&g) = s
                .collider_groups
                .iter()
                .find(|&&g| g >= self.collider_groups.len())
            {
                return bad(format!(
                    "{sname}: collider group {g} does not exist ({} groups)",
                    self.collider_groups.len()
                ));
            }
            let listed = s.collider_groups.iter().fold(0usize, |acc, &g| {
                acc.saturating_add(self.collider_groups[g].colliders.len())
            });
            pairs = pairs.saturating_add(listed.saturating_mul(s.joints.len()));
            if pairs > crate::limits::MAX_COLLIDER_PAIRS {
                return bad(format!(
                    "{sname}: the springs test more than {} joint-collider pairs per step \
                     (the limit)",
                    crate::limits::MAX_COLLIDER_PAIRS
                ));
            }
            if let Some(c) = s.center {
                if c >= n {
                    return bad(format!("{sname}: center joint {c} does not exist"));
                }
            }
            for j in &s.joints {
                if j.joint >= n {
                    return bad(format!(
                        "{sname}: joint {} does not exist ({n} joints)",
                        j.joint
                    ));
                }
                let what = format!("{sname}, joint {}", name(j.joint));
                if let Some(other) = owner[j.joint] {
                    return bad(if other == si {
                        format!("{what}: the joint is listed twice")
                    } else {
                        format!(
                            "{what}: the joint is already in VRM spring {other} ('{}'); a joint may belong to one spring only",
                            self.springs[other].name
                        )
                    });
                }
                owner[j.joint] = Some(si);
                match j.tail {
                    VrmTail::Joint(t) => {
                        if t >= n {
                            return bad(format!("{what}: tail joint {t} does not exist"));
                        }
                        if t == j.joint || !skeleton.is_descendant_of(t, j.joint) {
                            return bad(format!("{what}: tail {} is not below the joint", name(t)));
                        }
                    }
                    VrmTail::Local(p) => {
                        if !p.is_finite() || p.length_squared() < 1e-14 {
                            return bad(format!(
                                "{what}: the virtual tail {p} must be finite and non-zero"
                            ));
                        }
                    }
                }
                for (p, v) in [
                    ("hitRadius", j.hit_radius),
                    ("stiffness", j.stiffness),
                    ("gravityPower", j.gravity_power),
                ] {
                    if !v.is_finite() {
                        return Err(Error::NonFinite(format!("{what}: {p} {v}")));
                    }
                    if v < 0.0 {
                        return bad(format!("{what}: {p} {v} must be ≥ 0"));
                    }
                }
                if !j.gravity_dir.is_finite() {
                    return Err(Error::NonFinite(format!(
                        "{what}: gravityDir {}",
                        j.gravity_dir
                    )));
                }
                if !(j.drag_force.is_finite() && (0.0..=1.0).contains(&j.drag_force)) {
                    return bad(format!(
                        "{what}: dragForce {} must be in 0..=1",
                        j.drag_force
                    ));
                }
                if let Some(limit) = &j.limit {
                    limit.check().or_else(|m| bad(format!("{what}: {m}")))?;
                }
            }
        }
        Ok(())
    }
}

/// How the spring bones step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VrmMode {
    /// The specification's algorithm once per frame with the frame's `dt`, exactly as the
    /// specification and UniVRM run it (three-vrm too, but for its bone length: see
    /// [`VrmMode::ThreeVrm`]); the look depends on the frame rate. Ask for it by name for
    /// parity with the specification.
    Spec,
    /// The same update at a fixed internal rate, inputs interpolated within the frame; the
    /// output is the step that ends on the frame, else an output step (one update of the
    /// share of a step not yet stepped, on the frame's pose and colliders, not kept): the
    /// look does not depend on the frame rate, and the output is not a step late. The
    /// default.
    #[default]
    Fixed,
    /// three-vrm 3.5.5 as a web app runs it (`vrm.update(dt)`, then the render updates the
    /// world matrices): the specification's update once per frame, but each bone's length
    /// re-measured every update from the joint's current world position to where its tail
    /// node was at the end of the previous frame (the initial pose on the first frame; a
    /// virtual tail's own length), which lengthens and shortens bones while the character
    /// moves. Matches what users see in web viewers built on three-vrm.
    ThreeVrm,
}

/// Runtime options of the spring-bone solver (not part of the file). The default steps
/// [`VrmMode::Fixed`]; [`VrmOptions::spec`] gives the specification's stepping.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VrmOptions {
    /// Spec or fixed stepping.
    pub mode: VrmMode,
    /// Fixed mode: internal steps per second (10..=1000). 60 keeps the look the parameters
    /// were tuned for in a 60 fps editor.
    pub step_rate: f32,
    /// Fixed mode: at most this many steps per frame; a longer hitch drops time.
    pub max_steps_per_frame: u32,
    /// When the character moves more than this many metres in one frame the springs start
    /// again from the pose instead of whipping (0 = off, as the specification does).
    pub teleport_distance: f32,
}

impl Default for VrmOptions {
    fn default() -> Self {
        Self {
            mode: VrmMode::Fixed,
            step_rate: 60.0,
            max_steps_per_frame: 8,
            teleport_distance: 0.0,
        }
    }
}

impl VrmOptions {
    /// The default options with the specification's stepping ([`VrmMode::Spec`]).
    pub fn spec() -> Self {
        Self {
            mode: VrmMode::Spec,
            ..Self::default()
        }
    }

    /// Checks the options.
    pub fn validate(&self) -> Result<()> {
        if !(self.step_rate.is_finite() && (10.0..=1000.0).contains(&self.step_rate)) {
            return Err(Error::InvalidParameter(format!(
                "VRM step_rate {} must be in 10..=1000 steps per second",
                self.step_rate
            )));
        }
        let max_steps = crate::limits::MAX_STEPS_PER_FRAME;
        if !(1..=max_steps).contains(&self.max_steps_per_frame) {
            return Err(Error::InvalidParameter(format!(
                "VRM max_steps_per_frame {} must be 1..={max_steps}",
                self.max_steps_per_frame
            )));
        }
        if !(self.teleport_distance.is_finite() && self.teleport_distance >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "VRM teleport_distance {} must be finite and ≥ 0",
                self.teleport_distance
            )));
        }
        Ok(())
    }
}

/// A rig file's `[vrm]` table: how `fixed` mode steps the character's VRM spring bones
/// (the mode itself is chosen by `--mode`, not the file). Rig chains step at their own
/// `target_framerate`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct VrmStepping {
    /// Internal steps per second (10..=1000; default 60).
    pub step_rate: f32,
    /// At most this many steps in one frame; a longer hitch drops time (default 8).
    pub max_steps_per_frame: u32,
}

impl Default for VrmStepping {
    fn default() -> Self {
        let o = VrmOptions::default();
        Self {
            step_rate: o.step_rate,
            max_steps_per_frame: o.max_steps_per_frame,
        }
    }
}

impl VrmStepping {
    /// Whether every field has its default (the table is then not written).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// `options` with this stepping.
    pub fn apply(&self, options: VrmOptions) -> VrmOptions {
        VrmOptions {
            step_rate: self.step_rate,
            max_steps_per_frame: self.max_steps_per_frame,
            ..options
        }
    }
}
