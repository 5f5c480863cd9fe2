//! External forces on chains (KawaiiPhysics 1.16's `ExternalForces`): the `basic`,
//! `curve` and `gravity` presets of a rig file's `[[external_force]]` tables, forces
//! written in Rust ([`CustomForce`]), and the per-character state that sets, changes and
//! clears them at run time.
//!
//! Every step of a chain, each enabled force that reaches it is evaluated once (its clock,
//! its interval, its random scale: KawaiiPhysics' `PreApply`), then per point scaled by its
//! curve over the chain's length (`force_rate_by_bone_length_rate`) and added as
//! KawaiiPhysics adds it: `basic`, `curve` and custom forces move the point by
//! `force × dt` after the character's inertia and before the pull toward the pose
//! (`Apply`); `gravity` adds `force × dt` to the point's velocity before it moves
//! (`ApplyToVelocity`).

use super::compile::{ChainRig, VIRTUAL};
use super::wind::{GustRequest, ProceduralWindSettings, WindClock};
use crate::dynamics::Curve;
use crate::error::{Error, Result};
use crate::math::Transform;
use crate::rng::SplitMix64;
use crate::skeleton::Skeleton;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Which of KawaiiPhysics' force presets an `[[external_force]]` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceKind {
    /// A constant force (`force_dir`), optionally only once every `interval` seconds
    /// (`FKawaiiPhysics_ExternalForce_Basic`).
    #[default]
    Basic,
    /// A force that follows a curve over time (`force_curve`), looping
    /// (`FKawaiiPhysics_ExternalForce_Curve`).
    Curve,
    /// An acceleration added to the velocity, down or along `override_gravity_direction`
    /// (`FKawaiiPhysics_ExternalForce_Gravity`).
    Gravity,
    /// Wind made of parts over its own clock (`procedural_wind`: constant, sway, ripple,
    /// strength cycle, seeded noise, gusts; `FKawaiiPhysics_ExternalForce_ProceduralWind`).
    ProceduralWind,
}

/// The space a force's vector is given in (KawaiiPhysics' `EExternalForceSpace`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ForceSpace {
    /// The character's space: the force turns with the character.
    Component,
    /// World space (KawaiiPhysics' default).
    #[default]
    World,
    /// Each bone's animated space (rotation and scale; a dummy tip uses its parent bone).
    Bone,
}

/// How a `curve` force reads its curve over a step (KawaiiPhysics'
/// `EExternalForceCurveEvaluateType`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveEvaluate {
    /// The value at the step's end time.
    #[default]
    Single,
    /// The mean of `substep_count` values across the step.
    Average,
    /// The per-axis maximum of `substep_count` values across the step.
    Max,
    /// The per-axis minimum of `substep_count` values across the step.
    Min,
}

/// One external force (`[[external_force]]`): KawaiiPhysics' names in snake case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExternalForceSettings {
    /// Unique name: how the API and animation events refer to the force.
    pub name: String,
    /// The preset.
    pub kind: ForceKind,
    /// Whether the force acts (`bIsEnabled`); a disabled force can be enabled at run time.
    #[serde(rename = "is_enabled")]
    pub enabled: bool,
    /// The chains it acts on; empty: every chain.
    pub chains: Vec<String>,
    /// The bones it acts on (`ApplyBoneFilter`); empty: every simulated bone of its chains.
    pub apply_bone_filter: Vec<String>,
    /// The bones it never acts on (`IgnoreBoneFilter`).
    pub ignore_bone_filter: Vec<String>,
    /// The space of `force_dir` and `force_curve` (`ExternalForceSpace`; `gravity` is
    /// always in world space).
    pub external_force_space: ForceSpace,
    /// `basic`: the force, units per second² of push (`ForceDir`; its length is the
    /// strength).
    pub force_dir: Vec3,
    /// `basic`: act only on the first step after every `interval` seconds (0: every step).
    pub interval: f32,
    /// `curve`: keys `[time, x, y, z]` with increasing time, linear between keys, looped
    /// after the last key's time (`ForceCurve`).
    pub force_curve: Vec<[f32; 4]>,
    /// `curve`: how a step reads the curve (`CurveEvaluateType`).
    pub curve_evaluate_type: CurveEvaluate,
    /// `curve`: values per step for `average`, `max` and `min` (`SubstepCount`).
    pub substep_count: u32,
    /// `curve`: how fast the curve's time runs (`TimeScale`).
    pub time_scale: f32,
    /// `gravity`: use `override_gravity_direction` instead of down (−Y).
    pub use_override_gravity_direction: bool,
    /// `gravity`: the direction (normalised on use).
    pub override_gravity_direction: Vec3,
    /// A multiplier over the chain's normalised length, 0 at the root, 1 at the farthest
    /// tip (`ForceRateByBoneLengthRate`; empty: 1).
    pub force_rate_by_bone_length_rate: Curve,
    /// Each step scales the force by a random factor in `[min, max]`
    /// (`RandomForceScaleRange`; for `gravity` this is the strength).
    pub random_force_scale_range: [f32; 2],
    /// Seed of the random factor (Tassel's: every character and run draws the same), and
    /// of `procedural_wind`'s noise (its low 32 bits, KawaiiPhysics' `int32 Seed`).
    pub seed: u64,
    /// `procedural_wind`: its parts (`[external_force.procedural_wind]`).
    #[serde(skip_serializing_if = "ProceduralWindSettings::is_default")]
    pub procedural_wind: ProceduralWindSettings,
}

impl Default for ExternalForceSettings {
    fn default() -> Self {
        Self {
            name: String::new(),
            kind: ForceKind::Basic,
            enabled: true,
            chains: Vec::new(),
            apply_bone_filter: Vec::new(),
            ignore_bone_filter: Vec::new(),
            external_force_space: ForceSpace::World,
            force_dir: Vec3::ZERO,
            interval: 0.0,
            force_curve: Vec::new(),
            curve_evaluate_type: CurveEvaluate::Single,
            substep_count: 10,
            time_scale: 1.0,
            use_override_gravity_direction: false,
            override_gravity_direction: Vec3::ZERO,
            force_rate_by_bone_length_rate: Curve::default(),
            random_force_scale_range: [1.0, 1.0],
            seed: 1,
            procedural_wind: ProceduralWindSettings::default(),
        }
    }
}

impl ExternalForceSettings {
    /// Checks the values (not names: see [`ChainState::set_external_force`] and the rig's
    /// compile). Errors name the force.
    ///
    /// [`ChainState::set_external_force`]: super::ChainState::set_external_force
    pub fn validate(&self) -> Result<()> {
        let what = format!("external force '{}'", self.name);
        let bad = |msg: String| Err(Error::InvalidParameter(format!("{what}: {msg}")));
        if self.name.is_empty() {
            return Err(Error::InvalidParameter(
                "an [[external_force]] has no name".into(),
            ));
        }
        if !self.force_dir.is_finite() || self.force_dir.abs().max_element() > MAX_FORCE {
            return bad(format!(
                "force_dir must be finite, each axis within ±{MAX_FORCE:e}"
            ));
        }
        if !(self.interval.is_finite() && self.interval >= 0.0) {
            return bad(format!("interval {} must be ≥ 0", self.interval));
        }
        let [lo, hi] = self.random_force_scale_range;
        if !(lo.is_finite() && hi.is_finite() && lo <= hi && lo.abs().max(hi.abs()) <= MAX_FORCE) {
            return bad(format!(
                "random_force_scale_range [{lo}, {hi}] must be finite with min ≤ max"
            ));
        }
        if !(self.time_scale.is_finite() && (0.0..=1.0e3).contains(&self.time_scale)) {
            return bad(format!(
                "time_scale {} must be in 0..=1000",
                self.time_scale
            ));
        }
        if !(1..=MAX_SUBSTEPS).contains(&self.substep_count) {
            return bad(format!(
                "substep_count {} must be in 1..={MAX_SUBSTEPS}",
                self.substep_count
            ));
        }
        if self.force_curve.len() > MAX_CURVE_KEYS {
            return bad(format!("force_curve has more than {MAX_CURVE_KEYS} keys"));
        }
        for (i, k) in self.force_curve.iter().enumerate() {
            if !k.iter().all(|v| v.is_finite())
                || k[0] < 0.0
                || k[1..].iter().any(|v| v.abs() > MAX_FORCE)
            {
                return bad(format!(
                    "force_curve key {i} must be finite, its time ≥ 0 and its force within \
                     ±{MAX_FORCE:e}"
                ));
            }
            if i > 0 && k[0] <= self.force_curve[i - 1][0] {
                return bad(format!(
                    "force_curve key {i}'s time {} is not after the previous key's",
                    k[0]
                ));
            }
        }
        self.force_rate_by_bone_length_rate
            .validate(&format!("{what}: force_rate_by_bone_length_rate"))?;
        if !self.override_gravity_direction.is_finite() {
            return bad("override_gravity_direction is not finite".into());
        }
        if self.kind != ForceKind::ProceduralWind && !self.procedural_wind.is_default() {
            return bad("procedural_wind is for kind = \"procedural_wind\"".into());
        }
        match self.kind {
            ForceKind::ProceduralWind => {
                self.procedural_wind.validate(&what)?;
                if self.force_dir != Vec3::ZERO
                    || self.interval != 0.0
                    || !self.force_curve.is_empty()
                    || self.random_force_scale_range != [1.0, 1.0]
                {
                    return bad(
                        "a procedural wind takes its strength and direction from its \
                         procedural_wind table, not force_dir, interval, force_curve or \
                         random_force_scale_range"
                            .into(),
                    );
                }
            }
            ForceKind::Basic => {
                if !self.force_curve.is_empty() {
                    return bad("force_curve is for kind = \"curve\"".into());
                }
            }
            ForceKind::Curve => {
                if self.force_curve.is_empty() {
                    return bad("kind = \"curve\" needs force_curve keys".into());
                }
                if self.force_dir != Vec3::ZERO || self.interval != 0.0 {
                    return bad("force_dir and interval are for kind = \"basic\"".into());
                }
            }
            ForceKind::Gravity => {
                if self.external_force_space != ForceSpace::World {
                    return bad("a gravity force is in world space (as KawaiiPhysics')".into());
                }
                if self.force_dir != Vec3::ZERO || !self.force_curve.is_empty() {
                    return bad(
                        "a gravity force takes its strength from random_force_scale_range \
                         and its direction from override_gravity_direction, not force_dir or \
                         force_curve"
                            .into(),
                    );
                }
                if self.use_override_gravity_direction
                    && self.override_gravity_direction.length_squared() < 1e-12
                {
                    return bad("override_gravity_direction is zero".into());
                }
            }
        }
        Ok(())
    }
}

/// The largest force component or scale a force may have (units per second²).
const MAX_FORCE: f32 = 1.0e6;
/// The most keys of a `force_curve`.
const MAX_CURVE_KEYS: usize = 4_096;
/// The most values a `curve` force reads per step.
const MAX_SUBSTEPS: u32 = 1_000;

/// One step of one chain, as a [`CustomForce`] sees it.
#[derive(Debug, Clone, Copy)]
pub struct ForceStep {
    /// The chain's index in the rig.
    pub chain: usize,
    /// The step's length, seconds.
    pub dt: f32,
    /// Seconds of steps this chain has taken since the force was set, this step's end
    /// included.
    pub time: f64,
    /// The character's world transform at the step's end.
    pub component: Transform,
}

/// One point of a chain, as a [`CustomForce`] sees it (character space).
#[derive(Debug, Clone, Copy)]
pub struct ForcePoint {
    /// The point's index in the rig ([`ChainRig::point`]).
    pub point: usize,
    /// The joint it moves (`None`: a dummy tip).
    pub joint: Option<usize>,
    /// Its rest distance from the chain's root over the chain's longest (0..=1).
    pub length_rate: f32,
    /// Where it was at the end of the last step.
    pub position: Vec3,
    /// Where the animation puts it at this step's end.
    pub target: Vec3,
}

/// A force written in Rust (KawaiiPhysics' `UKawaiiPhysics_CustomExternalForce`): set with
/// [`crate::CharacterSim::set_custom_force`]. Its vector is read in its settings'
/// `external_force_space`, scaled by their `force_rate_by_bone_length_rate` and random
/// scale, filtered by their chains and bone filters, and moves the point by
/// `force × dt` as a `basic` force does. Called once per point per step, in a fixed
/// order: a deterministic force gives the same bits every run.
pub trait CustomForce: Send + Sync + std::fmt::Debug {
    /// The force on `point` this step (units per second² of push, in the settings' space).
    fn force(&self, step: &ForceStep, point: &ForcePoint) -> Vec3;
}

#[derive(Debug, Clone)]
enum Kind {
    Basic {
        dir: Vec3,
        interval: f32,
    },
    Curve {
        keys: Vec<[f32; 4]>,
        evaluate: CurveEvaluate,
        substeps: u32,
        time_scale: f32,
    },
    Gravity {
        dir: Vec3,
    },
    Wind(Box<ProceduralWindSettings>),
    Custom(Arc<dyn CustomForce>),
}

/// A force compiled against a chain rig: which points it reaches and at what rate.
#[derive(Debug, Clone)]
pub(crate) struct CompiledForce {
    name: String,
    kind: Kind,
    space: ForceSpace,
    range: [f32; 2],
    seed: u64,
    enabled: bool,
    /// Per chain: whether any of its points is reached.
    chains: Vec<bool>,
    /// Per point: the curve's rate, or `None` where the force does not act.
    rate: Vec<Option<f32>>,
}

impl CompiledForce {
    /// Compiles `s` for `rig` on `skeleton`; errors name the force and the entry.
    pub(crate) fn new(
        skeleton: &Skeleton,
        rig: &ChainRig,
        s: &ExternalForceSettings,
    ) -> Result<Self> {
        s.validate()?;
        let what = format!("external force '{}'", s.name);
        let mut chains = vec![s.chains.is_empty(); rig.chains.len()];
        for name in &s.chains {
            match rig.chains.iter().position(|c| &c.settings.name == name) {
                Some(ci) => chains[ci] = true,
                None => {
                    return Err(Error::InvalidParameter(format!(
                        "{what} names chain '{name}', which the rig does not define"
                    )))
                }
            }
        }
        let joints_of = |key: &str, names: &[String]| -> Result<Vec<usize>> {
            names
                .iter()
                .map(|n| {
                    let j = skeleton.find(n).ok_or_else(|| {
                        Error::InvalidParameter(format!(
                            "{what}: {key} names bone '{n}', which the skeleton does not have"
                        ))
                    })?;
                    let simulated = (0..rig.point_count()).any(|p| {
                        rig.joint[p] as usize == j
                            && rig.parent[p] != super::compile::NONE
                            && chains[rig.chain_of[p] as usize]
                    });
                    if !simulated {
                        return Err(Error::InvalidParameter(format!(
                            "{what}: {key} names bone '{n}', which none of its chains simulates"
                        )));
                    }
                    Ok(j)
                })
                .collect()
        };
        let apply = joints_of("apply_bone_filter", &s.apply_bone_filter)?;
        let ignore = joints_of("ignore_bone_filter", &s.ignore_bone_filter)?;
        let rate = (0..rig.point_count())
            .map(|p| {
                let j = rig.joint[p];
                let joint = (j != VIRTUAL).then_some(j as usize);
                // KawaiiPhysics' filters hold bone references: a dummy tip is in neither.
                let reached = chains[rig.chain_of[p] as usize]
                    && rig.parent[p] != super::compile::NONE
                    && (apply.is_empty() || joint.is_some_and(|j| apply.contains(&j)))
                    && !joint.is_some_and(|j| ignore.contains(&j));
                reached.then(|| s.force_rate_by_bone_length_rate.eval(rig.length_rate[p]))
            })
            .collect::<Vec<_>>();
        for (ci, c) in rig.chains.iter().enumerate() {
            chains[ci] = c.points.clone().any(|p| rate[p].is_some());
        }
        let kind = match s.kind {
            ForceKind::Basic => Kind::Basic {
                dir: s.force_dir,
                interval: s.interval,
            },
            ForceKind::Curve => Kind::Curve {
                keys: s.force_curve.clone(),
                evaluate: s.curve_evaluate_type,
                substeps: s.substep_count,
                time_scale: s.time_scale,
            },
            ForceKind::Gravity => Kind::Gravity {
                dir: if s.use_override_gravity_direction {
                    s.override_gravity_direction.normalize()
                } else {
                    Vec3::NEG_Y
                },
            },
            ForceKind::ProceduralWind => Kind::Wind(Box::new(s.procedural_wind.clone())),
        };
        Ok(Self {
            name: s.name.clone(),
            kind,
            space: s.external_force_space,
            range: s.random_force_scale_range,
            seed: s.seed,
            enabled: s.enabled,
            chains,
            rate,
        })
    }
}

/// `keys` (`[t, x, y, z]`, increasing t) at time `t`, linear between keys, held at both
/// ends.
fn curve_at(keys: &[[f32; 4]], t: f32) -> Vec3 {
    let v = |k: &[f32; 4]| Vec3::new(k[1], k[2], k[3]);
    match crate::dynamics::curve::bracket(keys, t, |k| k[0]) {
        None => Vec3::ZERO,
        Some((i, j, w)) => v(&keys[i]) + (v(&keys[j]) - v(&keys[i])) * w,
    }
}

/// Per chain: a force's clock and random generator.
#[derive(Debug, Clone)]
struct Clock {
    /// The interval's or the curve's time.
    time: f32,
    /// Seconds of steps since the force was set.
    elapsed: f64,
    rng: SplitMix64,
    /// A one-shot force has acted on this chain.
    fired: bool,
    /// `procedural_wind`: its own clock and gusts.
    wind: WindClock,
}

#[derive(Debug, Clone)]
struct Active {
    force: Arc<CompiledForce>,
    enabled: bool,
    one_shot: bool,
    clocks: Vec<Clock>,
}

impl Active {
    fn new(force: Arc<CompiledForce>, chains: usize) -> Self {
        let clocks = (0..chains)
            .map(|ci| Clock {
                time: 0.0,
                elapsed: 0.0,
                rng: SplitMix64::new(force.seed ^ ((ci as u64) << 32) ^ 0x4B50_4652),
                fired: false,
                wind: WindClock::default(),
            })
            .collect();
        Self {
            enabled: force.enabled,
            force,
            one_shot: false,
            clocks,
        }
    }
}

/// A character's external forces: the rig's and those set at run time, their clocks, and
/// the scratch one step of a chain reads.
#[derive(Debug, Clone, Default)]
pub(crate) struct Forces {
    list: Vec<Active>,
    /// Per point, this step: the push (`x += push × dt`) and the acceleration
    /// (`v += accel × dt`).
    pub(crate) push: Vec<Vec3>,
    pub(crate) accel: Vec<Vec3>,
    /// Per point: its bone's animated model transform this frame and last frame (bone
    /// space forces), and whether last frame's is missing.
    bone: Vec<Transform>,
    prev_bone: Vec<Transform>,
    bones_fresh: bool,
}

impl Forces {
    /// The rig's forces, as the rig file sets them.
    pub(crate) fn new(rig: &ChainRig) -> Self {
        let mut f = Self::default();
        for force in &rig.forces {
            f.insert(rig, force.clone(), false);
        }
        f
    }

    fn insert(&mut self, rig: &ChainRig, force: Arc<CompiledForce>, one_shot: bool) {
        let n = rig.point_count();
        if self.push.len() != n {
            self.push = vec![Vec3::ZERO; n];
            self.accel = vec![Vec3::ZERO; n];
        }
        if force.space == ForceSpace::Bone && self.bone.len() != n {
            self.bone = vec![Transform::IDENTITY; n];
            self.prev_bone = vec![Transform::IDENTITY; n];
            self.bones_fresh = true;
        }
        let mut active = Active::new(force, rig.chains.len());
        if one_shot {
            // Beside the named force, on, with clocks of its own; never found by name.
            active.one_shot = true;
            active.enabled = true;
            self.list.push(active);
            return;
        }
        match self.named_mut(&active.force.name) {
            Some(a) => *a = active,
            None => self.list.push(active),
        }
    }

    /// The named force (one-shots are not found by name).
    fn named_mut(&mut self, name: &str) -> Option<&mut Active> {
        self.list
            .iter_mut()
            .find(|a| !a.one_shot && a.force.name == name)
    }

    /// Adds or replaces (by name) a compiled force.
    pub(crate) fn set(&mut self, rig: &ChainRig, force: CompiledForce) {
        self.insert(rig, Arc::new(force), false);
    }

    /// Turns the named force on or off; false when there is none of that name.
    pub(crate) fn enable(&mut self, name: &str, on: bool) -> bool {
        match self.named_mut(name) {
            Some(a) => {
                a.enabled = on;
                true
            }
            None => false,
        }
    }

    /// The named force for one step of each chain it reaches, then gone: the same compiled
    /// force with clocks of its own (KawaiiPhysics' one-shot forces of anim notifies).
    /// False when there is no force of that name.
    pub(crate) fn once(&mut self, rig: &ChainRig, name: &str) -> bool {
        let Some(force) = self.named_mut(name).map(|a| a.force.clone()) else {
            return false;
        };
        self.insert(rig, force, true);
        true
    }

    /// Starts a gust of the named procedural wind on each chain it reaches, at that chain's
    /// next step. `None` when there is no force of that name, `Some(false)` when it is not
    /// a procedural wind.
    pub(crate) fn gust(&mut self, name: &str, request: GustRequest) -> Option<bool> {
        let a = self.named_mut(name)?;
        if !matches!(a.force.kind, Kind::Wind(_)) {
            return Some(false);
        }
        for c in &mut a.clocks {
            c.wind.starts.push(request);
            if c.wind.starts.len() > super::wind::MAX_GUSTS {
                c.wind.starts.remove(0);
            }
        }
        Some(true)
    }

    /// Fades every gust of the named procedural wind out over `blend_out` seconds of its
    /// clock (0: at once), from each chain's next step; as [`Forces::gust`].
    pub(crate) fn stop_gusts(&mut self, name: &str, blend_out: f32) -> Option<bool> {
        let a = self.named_mut(name)?;
        if !matches!(a.force.kind, Kind::Wind(_)) {
            return Some(false);
        }
        for c in &mut a.clocks {
            c.wind.stop = Some(blend_out);
        }
        Some(true)
    }

    /// The named procedural wind's parts on chain `ci` as its last step left them (its
    /// clock's time, the sample at the root, the direction in the force's space).
    pub(crate) fn wind_state(
        &self,
        name: &str,
        ci: usize,
    ) -> Option<(f32, super::wind::WindSample, Vec3)> {
        let a = self
            .list
            .iter()
            .find(|a| !a.one_shot && a.force.name == name)?;
        let Kind::Wind(w) = &a.force.kind else {
            return None;
        };
        let c = a.clocks.get(ci)?;
        let gust = c.wind.gusts.iter().map(|g| g.at(c.wind.time)).sum();
        Some((
            c.wind.time,
            w.sample(c.wind.time, 0.0, gust, a.force.seed),
            w.direction(c.wind.time, a.force.seed),
        ))
    }

    /// Removes the named force (not its one-shots under way); false when there is none.
    pub(crate) fn remove(&mut self, name: &str) -> bool {
        let before = self.list.len();
        self.list.retain(|a| a.one_shot || a.force.name != name);
        self.list.len() != before
    }

    /// Removes every force (the rig's too).
    pub(crate) fn clear(&mut self) {
        self.list.clear();
    }

    /// The forces' names and whether each is on (one-shots left out).
    pub(crate) fn names(&self) -> impl Iterator<Item = (&str, bool)> + '_ {
        self.list
            .iter()
            .filter(|a| !a.one_shot)
            .map(|a| (a.force.name.as_str(), a.enabled))
    }

    /// Whether every force was compiled for `rig`'s points and chains.
    pub(crate) fn fits(&self, rig: &ChainRig) -> bool {
        let (n, c) = (rig.point_count(), rig.chains.len());
        ((self.push.is_empty() && self.list.is_empty())
            || (self.push.len() == n && self.accel.len() == n))
            && (self.bone.is_empty() || (self.bone.len() == n && self.prev_bone.len() == n))
            && self.list.iter().all(|a| {
                a.force.rate.len() == n && a.force.chains.len() == c && a.clocks.len() == c
            })
    }

    /// Whether any force is on: then the character's chains step on the scalar path.
    pub(crate) fn any(&self) -> bool {
        self.list.iter().any(|a| a.enabled)
    }

    /// Whether chain `ci` has a force on.
    pub(crate) fn reaches(&self, ci: usize) -> bool {
        self.list.iter().any(|a| a.enabled && a.force.chains[ci])
    }

    /// Reads the bones' animated transforms of this frame (bone-space forces only).
    pub(crate) fn gather_bones(&mut self, rig: &ChainRig, models: &[Transform]) {
        let needed = self
            .list
            .iter()
            .any(|a| a.enabled && a.force.space == ForceSpace::Bone);
        if !needed || self.bone.len() != rig.point_count() {
            return;
        }
        for p in 0..rig.point_count() {
            let mut j = rig.joint[p];
            if j == VIRTUAL {
                j = rig.joint[rig.real_parent[p] as usize];
            }
            self.bone[p] = models[j as usize];
        }
        if self.bones_fresh {
            self.prev_bone.copy_from_slice(&self.bone);
            self.bones_fresh = false;
        }
    }

    /// End of a frame: this frame's bones become last frame's; spent one-shots go.
    pub(crate) fn end_frame(&mut self) {
        if !self.bone.is_empty() && !self.bones_fresh {
            self.prev_bone.copy_from_slice(&self.bone);
        }
        self.list.retain(|a| {
            !(a.one_shot
                && a.force
                    .chains
                    .iter()
                    .zip(&a.clocks)
                    .all(|(&reached, c)| !reached || c.fired))
        });
    }

    /// Fills `push` and `accel` of chain `ci`'s points for one step of `dt` ending at
    /// share `w` of the frame, the character at `component`, the points at `pos` and the
    /// targets at `targets`. Returns whether anything acts.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn prepare(
        &mut self,
        rig: &ChainRig,
        ci: usize,
        dt: f32,
        w: f32,
        component: &Transform,
        pos: &[Vec3],
        targets: &[Vec3],
    ) -> bool {
        let points = rig.chains[ci].points.clone();
        if !self.reaches(ci) {
            return false;
        }
        for p in points.clone() {
            self.push[p] = Vec3::ZERO;
            self.accel[p] = Vec3::ZERO;
        }
        let to_cs = component.rotation.inverse();
        let Forces {
            list,
            push,
            accel,
            bone,
            prev_bone,
            ..
        } = self;
        for a in list.iter_mut().filter(|a| a.enabled && a.force.chains[ci]) {
            let f = &*a.force;
            let clock = &mut a.clocks[ci];
            clock.elapsed += dt as f64;
            clock.fired = true;
            let scale = clock.rng.range_f32(f.range[0], f.range[1]);
            let step = ForceStep {
                chain: ci,
                dt,
                time: clock.elapsed,
                component: *component,
            };
            // The force this step in its own space (custom forces and winds: per point,
            // below).
            let mut wind_step = None;
            let v = match &f.kind {
                Kind::Basic { dir, interval } => {
                    clock.time += dt;
                    if *interval > 0.0 {
                        if clock.time > *interval {
                            clock.time %= *interval;
                            *dir * scale
                        } else {
                            Vec3::ZERO
                        }
                    } else {
                        *dir * scale
                    }
                }
                Kind::Curve {
                    keys,
                    evaluate,
                    substeps,
                    time_scale,
                } => {
                    let max_time = keys.last().map_or(0.0, |k| k[0]);
                    let mut advance = |by: f32| {
                        clock.time += by;
                        if max_time > 0.0 && clock.time > max_time {
                            clock.time %= max_time;
                        }
                        curve_at(keys, clock.time)
                    };
                    let value = match evaluate {
                        CurveEvaluate::Single => advance(dt * time_scale),
                        _ => {
                            let sub = dt * time_scale / *substeps as f32;
                            let first = advance(sub);
                            let (mut sum, mut hi, mut lo) = (first, first, first);
                            for _ in 1..*substeps {
                                let v = advance(sub);
                                sum += v;
                                hi = hi.max(v);
                                lo = lo.min(v);
                            }
                            match evaluate {
                                CurveEvaluate::Average => sum / *substeps as f32,
                                CurveEvaluate::Max => hi,
                                _ => lo,
                            }
                        }
                    };
                    value * scale
                }
                Kind::Gravity { dir } => *dir * scale,
                Kind::Wind(wind) => {
                    // Its clock and gusts; the parts every point shares (the ripple is
                    // per point, below).
                    let gust = clock.wind.step(dt, wind.time_scale);
                    let t = clock.wind.time;
                    let at_root = wind.sample(t, 0.0, gust, f.seed);
                    wind_step = Some((at_root, wind.direction(t, f.seed), t));
                    Vec3::ZERO
                }
                Kind::Custom(_) => Vec3::ZERO,
            };
            let in_cs = |v: Vec3, p: usize| -> Vec3 {
                match f.space {
                    ForceSpace::Component => v,
                    ForceSpace::World => to_cs * v,
                    ForceSpace::Bone => {
                        let (a, b) = (&prev_bone[p], &bone[p]);
                        if w >= 1.0 {
                            b.rotation * (b.scale * v)
                        } else {
                            a.rotation.lerp(b.rotation, w) * (a.scale.lerp(b.scale, w) * v)
                        }
                    }
                }
            };
            for p in points.clone() {
                let Some(rate) = f.rate[p] else { continue };
                let v = match &f.kind {
                    Kind::Custom(custom) => {
                        let j = rig.joint[p];
                        let point = ForcePoint {
                            point: p,
                            joint: (j != VIRTUAL).then_some(j as usize),
                            length_rate: rig.length_rate[p],
                            position: pos[p],
                            target: targets[p],
                        };
                        let v = custom.force(&step, &point);
                        if !v.is_finite() {
                            continue;
                        }
                        v * scale
                    }
                    Kind::Wind(wind) => {
                        // KawaiiPhysics' `Apply`: the ripple at the point's length rate.
                        let (s, dir, t) = wind_step.expect("set above");
                        let ripple = wind.ripple(t, rig.length_rate[p]);
                        let total =
                            (s.constant + s.sway + ripple) * s.strength_cycle + s.random + s.gust;
                        dir * total
                    }
                    _ => v,
                };
                let force = in_cs(v, p) * rate;
                match f.kind {
                    Kind::Gravity { .. } => accel[p] += force,
                    _ => push[p] += force,
                }
            }
        }
        true
    }
}

/// A custom force compiled from its settings (their `kind` ignored).
pub(crate) fn compile_custom(
    skeleton: &Skeleton,
    rig: &ChainRig,
    settings: &ExternalForceSettings,
    force: Arc<dyn CustomForce>,
) -> Result<CompiledForce> {
    let mut s = settings.clone();
    // Checked as a basic force: the vector comes from the trait.
    s.kind = ForceKind::Basic;
    s.force_curve.clear();
    let mut c = CompiledForce::new(skeleton, rig, &s)?;
    c.kind = Kind::Custom(force);
    Ok(c)
}
