//! Per-character chain state and the frame job.

use super::compile::{ChainRig, NONE, VIRTUAL};
use super::constraint::ChainGroup;
use super::settings::TimeMode;
use super::step::{step_chain, step_group, Bridges, GroupRef, StepInput};
use crate::collide::{NearSet, PlacedCollider};
use crate::controller::Level;
use crate::dynamics::chain::lanes::twins::{ChainLanes, LaneFrame, ScalarChains};
use crate::dynamics::path::CharacterPath;
use crate::dynamics::world::{push_out, WorldContact};
use crate::error::{Error, Result};
use crate::lanes::{Isa, SimdUse};
use crate::math::{normalize_or, rotation_arc, Transform};
use crate::rng::SplitMix64;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3, Vec4};

/// The small per-character state of a [`ChainRig`]: point positions and the previous
/// frame's inputs. Changes only through [`ChainJob::run`], [`ChainState::reset`] and
/// [`ChainState::teleport`].
#[derive(Debug, Clone)]
pub struct ChainState {
    /// The character's recent transforms: where it was at each step's time.
    path: CharacterPath,
    pos: Vec<Vec3>,
    prev: Vec<Vec3>,
    // Deviation from the targets the output pass blends by alpha (equal: the output pass
    // interpolates between them at the frame's end, which is `dev`).
    dev: Vec<Vec3>,
    dev_before: Vec<Vec3>,
    out: Vec<Vec3>,
    /// Scratch of fixed mode's output step ([`output_step`]): the previous positions it
    /// moves (its positions are `out`), and the wind generators it draws from, so that
    /// the kept state is not touched.
    keep_prev: Vec<Vec3>,
    keep_rng: Vec<SplitMix64>,
    /// Bridge points on the bone constraints (`bone_constraint_subdivision_count`): their
    /// places after the last step and before it; the output step's copies; per point the
    /// pushes they feed back (empty without bridges).
    bridge_pos: Vec<Vec3>,
    bridge_prev: Vec<Vec3>,
    /// The bridge points as the frame outputs them (fixed mode's output step's).
    bridge_out: Vec<Vec3>,
    keep_bridge_pos: Vec<Vec3>,
    keep_bridge_prev: Vec<Vec3>,
    feedback: Vec<Vec4>,
    targets: Vec<Vec3>,
    prev_targets: Vec<Vec3>,
    step_targets: Vec<Vec3>,
    normals: Vec<Vec3>,
    prev_normals: Vec<Vec3>,
    step_normals: Vec<Vec3>,
    colliders: Vec<PlacedCollider>,
    prev_colliders: Vec<PlacedCollider>,
    step_colliders: Vec<PlacedCollider>,
    /// The bounding spheres of `colliders` and `step_colliders`, for the broad phase.
    bounds: Vec<Vec4>,
    step_bounds: Vec<Vec4>,
    /// The share of the frame each `step_colliders` entry was placed at (bits), NaN when
    /// it is not this frame's: chains stepping at the same times (the usual case: one
    /// rate for all) place each shared collider once.
    step_placed_at: Vec<f32>,
    prev_component: Transform,
    last_step_component: Vec<Transform>,
    accumulator: Vec<f32>,
    dt_old: Vec<f32>,
    rng: Vec<SplitMix64>,
    needs_reset: Vec<bool>,
    teleports: u64,
    /// Which code steps the rig's twin chains ([`ChainRig::lane_groups`]).
    simd: SimdUse,
    /// Each lane group's state, authoritative for its chains while `in_lanes`.
    lanes: Vec<ChainLanes>,
    in_lanes: bool,
    /// Scratch of the lanes' write-back: each rotator row between its two passes.
    turned: Vec<crate::dynamics::chain::lanes::twins::TurnedRow>,
    /// Scratch of a bone-constraint group's step: the constraints' Lagrange multipliers,
    /// and per chain whether the world is near.
    lambda: Vec<f32>,
    world_near: Vec<bool>,
    /// The targets as the animation places them, before sync bones moved them (the
    /// write-back turns bones from these); empty without sync bones.
    animated: Vec<Vec3>,
    /// External forces: the rig's and those set at run time.
    forces: super::force::Forces,
    /// Per chain: the alpha set at run time (multiplies the chain's `alpha`).
    alpha: Vec<f32>,
    /// Per chain (`base_bone` space): the base bone's model transform this frame, last
    /// frame, and at the chain's last step.
    base_now: Vec<Transform>,
    base_prev: Vec<Transform>,
    last_step_base: Vec<Transform>,
    /// Scratch of a group's step: per chain, the motion its step reads ([`space_step`]).
    space_in: Vec<SpaceIn>,
    /// Timed settings overrides, and the per-point settings they scale.
    overrides: super::overrides::Overrides,
    params: super::overrides::ScaledParams,
    /// Colliders other characters share with this one (world space; placed into this
    /// character's space each frame after the rig's, at indices `rig.colliders.len()..`),
    /// per chain that uses them its collider list with theirs (empty: the rig's list),
    /// every collider's index (the bridge points'), and whether their placement of last
    /// frame is missing (set, or their count changed).
    shared: Vec<PlacedCollider>,
    shared_lists: Vec<Vec<usize>>,
    every: Vec<usize>,
    shared_fresh: bool,
}

/// What one chain's step reads of the character's motion ([`space_step`]).
type SpaceIn = (Vec3, Quat, Option<(Transform, Transform)>);

impl ChainState {
    /// Fresh state for `rig`; the first frame resets it to the animated pose.
    pub fn new(rig: &ChainRig) -> Self {
        let n = rig.point_count();
        let m = rig.colliders.len();
        let c = rig.chains.len();
        let placed = PlacedCollider {
            shape: crate::collide::Shape::Plane,
            transform: Transform::IDENTITY,
        };
        Self {
            path: CharacterPath::default(),
            pos: vec![Vec3::ZERO; n],
            prev: vec![Vec3::ZERO; n],
            dev: vec![Vec3::ZERO; n],
            dev_before: vec![Vec3::ZERO; n],
            out: vec![Vec3::ZERO; n],
            keep_prev: vec![Vec3::ZERO; n],
            keep_rng: (0..c).map(|ci| chain_rng(rig, ci)).collect(),
            bridge_pos: vec![Vec3::ZERO; rig.constraints.bridges.len()],
            bridge_prev: vec![Vec3::ZERO; rig.constraints.bridges.len()],
            bridge_out: vec![Vec3::ZERO; rig.constraints.bridges.len()],
            keep_bridge_pos: vec![Vec3::ZERO; rig.constraints.bridges.len()],
            keep_bridge_prev: vec![Vec3::ZERO; rig.constraints.bridges.len()],
            feedback: if rig.constraints.bridges.is_empty() {
                Vec::new()
            } else {
                vec![Vec4::ZERO; n]
            },
            targets: vec![Vec3::ZERO; n],
            prev_targets: vec![Vec3::ZERO; n],
            step_targets: vec![Vec3::ZERO; n],
            normals: vec![Vec3::Y; n],
            prev_normals: vec![Vec3::Y; n],
            step_normals: vec![Vec3::Y; n],
            colliders: vec![placed; m],
            prev_colliders: vec![placed; m],
            step_colliders: vec![placed; m],
            bounds: vec![Vec4::ZERO; m],
            step_bounds: vec![Vec4::ZERO; m],
            step_placed_at: vec![f32::NAN; m],
            prev_component: Transform::IDENTITY,
            last_step_component: vec![Transform::IDENTITY; c],
            accumulator: vec![0.0; c],
            dt_old: vec![0.0; c],
            rng: (0..c).map(|ci| chain_rng(rig, ci)).collect(),
            needs_reset: vec![true; c],
            teleports: 0,
            simd: SimdUse::default(),
            lanes: rig.lane_groups.iter().map(ChainLanes::new).collect(),
            in_lanes: false,
            turned: Vec::with_capacity(rig.rotators.len()),
            lambda: vec![0.0; rig.constraints.list.len()],
            world_near: vec![false; c],
            animated: if rig.syncs.is_empty() {
                Vec::new()
            } else {
                vec![Vec3::ZERO; n]
            },
            forces: super::force::Forces::new(rig),
            alpha: vec![1.0; c],
            base_now: vec![Transform::IDENTITY; c],
            base_prev: vec![Transform::IDENTITY; c],
            last_step_base: vec![Transform::IDENTITY; c],
            space_in: vec![(Vec3::ZERO, Quat::IDENTITY, None); c],
            overrides: Default::default(),
            params: super::overrides::ScaledParams::new(rig),
            shared: Vec::new(),
            shared_lists: Vec::new(),
            every: Vec::new(),
            shared_fresh: false,
        }
    }

    /// Which code steps the twin chains: lanes by default ([`SimdUse::Auto`]),
    /// [`SimdUse::Scalar`] for the readable reference. Every choice gives the same bits;
    /// a change takes effect on the next frame, carrying the chains' state over.
    pub fn set_simd(&mut self, simd: SimdUse) {
        self.simd = simd;
    }

    /// The code chosen by [`ChainState::set_simd`].
    pub fn simd(&self) -> SimdUse {
        self.simd
    }

    /// Moves the lane groups' chains into their lanes (`to_lanes`) or back into the scalar
    /// arrays.
    fn move_lanes(&mut self, rig: &ChainRig, to_lanes: bool) {
        let mut scalar = ScalarChains {
            pos: &mut self.pos,
            prev: &mut self.prev,
            dev: &mut self.dev,
            dev_before: &mut self.dev_before,
            prev_targets: &mut self.prev_targets,
            prev_normals: &mut self.prev_normals,
            prev_colliders: &self.prev_colliders,
            last_step_component: &mut self.last_step_component,
            accumulator: &mut self.accumulator,
            dt_old: &mut self.dt_old,
            rng: &mut self.rng,
            needs_reset: &mut self.needs_reset,
            path: &self.path,
            prev_component: self.prev_component,
            teleports: &mut self.teleports,
        };
        for (lanes, group) in self.lanes.iter_mut().zip(&rig.lane_groups) {
            if to_lanes {
                lanes.load(rig, group, &mut scalar);
            } else {
                lanes.store(rig, group, &mut scalar);
            }
        }
        self.in_lanes = to_lanes;
    }

    /// Makes the next frame start again from the animated pose (velocities zero), wherever
    /// the character was before (its path is forgotten: that frame's time step changes
    /// nothing).
    pub fn reset(&mut self) {
        self.needs_reset.iter_mut().for_each(|r| *r = true);
        // Where the character was is no part of where it goes from here.
        self.path = CharacterPath::default();
        self.lanes.iter_mut().for_each(ChainLanes::reset);
    }

    /// Tells the state that the character was moved on purpose: the next frame resets the
    /// chains instead of swinging them from the old place.
    pub fn teleport(&mut self) {
        self.reset();
    }

    /// Adds an external force, or replaces the one of the same name (its clock starts
    /// again), compiled for `rig` on `skeleton` (the rig and skeleton this state was made
    /// for). Errors name the force and what is wrong; the forces are unchanged then.
    pub fn set_external_force(
        &mut self,
        skeleton: &Skeleton,
        rig: &ChainRig,
        settings: &super::ExternalForceSettings,
    ) -> Result<()> {
        self.check_rig(rig)?;
        let force = super::force::CompiledForce::new(skeleton, rig, settings)?;
        self.forces.set(rig, force);
        Ok(())
    }

    /// Adds (or replaces by name) a force written in Rust: `settings` give its name,
    /// chains, bone filters, space, rate curve and random scale (their `kind` and
    /// vectors are not read); `force` gives the vector per point and step.
    pub fn set_custom_force(
        &mut self,
        skeleton: &Skeleton,
        rig: &ChainRig,
        settings: &super::ExternalForceSettings,
        force: std::sync::Arc<dyn super::CustomForce>,
    ) -> Result<()> {
        self.check_rig(rig)?;
        let force = super::force::compile_custom(skeleton, rig, settings, force)?;
        self.forces.set(rig, force);
        Ok(())
    }

    /// Turns the named external force on or off (it keeps its clock); false when there
    /// is none of that name.
    pub fn enable_external_force(&mut self, name: &str, on: bool) -> bool {
        self.forces.enable(name, on)
    }

    /// Applies the named external force for one step of each chain it reaches, on or off
    /// (KawaiiPhysics' one-shot forces of anim notifies); false when there is none.
    pub fn external_force_once(&mut self, rig: &ChainRig, name: &str) -> bool {
        self.check_rig(rig).is_ok() && self.forces.once(rig, name)
    }

    /// Removes the named external force; false when there is none.
    pub fn remove_external_force(&mut self, name: &str) -> bool {
        self.forces.remove(name)
    }

    /// Removes every external force, the rig file's included.
    pub fn clear_external_forces(&mut self) {
        self.forces.clear();
    }

    /// The external forces' names, each with whether it is on.
    pub fn external_forces(&self) -> impl Iterator<Item = (&str, bool)> + '_ {
        self.forces.names()
    }

    /// Sets the colliders other characters share with this one (world space: each placed
    /// where it is this frame, e.g. from [`crate::CharacterSim::shared_colliders`]), for
    /// this frame and the next until set again or cleared; the chains with
    /// `use_shared_collision` collide with them after the rig's own. Set them every frame
    /// for colliders that move: each frame places them in the character's space and
    /// sweeps points against their motion since the last frame (when their count stays
    /// the same). Errors name a shape out of range or a transform that is not finite;
    /// nothing changes then.
    pub fn set_shared_colliders(&mut self, rig: &ChainRig, world: &[PlacedCollider]) -> Result<()> {
        self.check_rig(rig)?;
        if world.len() > crate::limits::MAX_COLLIDERS {
            return Err(Error::InvalidParameter(format!(
                "{} shared colliders, more than the limit of {}",
                world.len(),
                crate::limits::MAX_COLLIDERS
            )));
        }
        for (i, c) in world.iter().enumerate() {
            let what = format!("shared collider {i}");
            c.shape.validate(&what)?;
            let t = &c.transform;
            if !(t.translation.is_finite() && t.rotation.is_finite())
                || t.rotation.length() < 1e-6
                || !t.within_limits()
            {
                return Err(Error::InvalidParameter(format!(
                    "{what}: its transform is not finite (or beyond the coordinate limit)"
                )));
            }
        }
        let m = rig.colliders.len();
        let k = world.len();
        if k != self.shared.len() {
            let n = m + k;
            let placed = PlacedCollider {
                shape: crate::collide::Shape::Plane,
                transform: Transform::IDENTITY,
            };
            self.colliders.resize(n, placed);
            self.prev_colliders.resize(n, placed);
            self.step_colliders.resize(n, placed);
            self.bounds.resize(n, Vec4::ZERO);
            self.step_bounds.resize(n, Vec4::ZERO);
            self.step_placed_at.resize(n, f32::NAN);
            self.shared_fresh = true;
        }
        self.shared.clear();
        self.shared.extend(world.iter().map(|c| PlacedCollider {
            shape: c.shape,
            transform: Transform::from_translation_rotation(
                c.transform.translation,
                c.transform.rotation.normalize(),
            ),
        }));
        self.shared_lists = if k == 0 {
            Vec::new()
        } else {
            rig.chains
                .iter()
                .map(|c| {
                    if c.settings.use_shared_collision {
                        c.colliders.iter().copied().chain(m..m + k).collect()
                    } else {
                        Vec::new()
                    }
                })
                .collect()
        };
        self.every = if k == 0 {
            Vec::new()
        } else {
            (0..m + k).collect()
        };
        Ok(())
    }

    /// The colliders shared with this character, as set (world space).
    pub fn shared_colliders(&self) -> &[PlacedCollider] {
        &self.shared
    }

    /// Starts a gust of the procedural wind named `name` (an `[[external_force]]` of kind
    /// `procedural_wind`) on each chain it reaches, from that chain's next step; gusts
    /// stack, up to [`super::MAX_GUSTS`]. Errors name a bad gust, a force that does not
    /// exist or is not a procedural wind.
    pub fn trigger_wind_gust(&mut self, name: &str, gust: super::GustRequest) -> Result<()> {
        gust.check()?;
        self.wind_result(name, |f| f.gust(name, gust))
    }

    /// Fades every gust of the procedural wind `name` out over `blend_out` seconds of its
    /// clock (0: at once); errors as [`ChainState::trigger_wind_gust`].
    pub fn stop_wind_gusts(&mut self, name: &str, blend_out: f32) -> Result<()> {
        if !(blend_out.is_finite() && blend_out >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "stopping the gusts of '{name}': blend_out {blend_out} s is not a time ≥ 0"
            )));
        }
        self.wind_result(name, |f| f.stop_gusts(name, blend_out))
    }

    fn wind_result(
        &mut self,
        name: &str,
        act: impl FnOnce(&mut super::force::Forces) -> Option<bool>,
    ) -> Result<()> {
        match act(&mut self.forces) {
            Some(true) => Ok(()),
            Some(false) => Err(Error::InvalidParameter(format!(
                "external force '{name}' is not a procedural wind"
            ))),
            None => Err(Error::InvalidParameter(format!(
                "there is no external force named '{name}'"
            ))),
        }
    }

    /// The procedural wind `name` on chain `ci` as its last step left it: its clock's time,
    /// its parts at the chain's root ([`super::WindSample`]) and its unit direction in the
    /// force's space. `None` for another kind of force, a name or chain that does not
    /// exist.
    pub fn wind_sample(&self, name: &str, ci: usize) -> Option<(f32, super::WindSample, Vec3)> {
        self.forces.wind_state(name, ci)
    }

    /// Starts a timed settings override (KawaiiPhysics' `StartPhysicsSettingsOverride`):
    /// `scale` multiplies the settings of `chains` (`None`: every chain) over `timing`,
    /// from the next frame (in `fixed` mode, its clock starts now, between frames, and each
    /// step reads it at its own time: the same look at every frame rate). A `name` lets
    /// animation events stop it; starting a name again
    /// blends the older one out over the new one's blend-in. Errors name a bad scale, time
    /// or chain; nothing is queued then.
    pub fn start_settings_override(
        &mut self,
        rig: &ChainRig,
        scale: super::SettingsScale,
        timing: super::OverrideTiming,
        chains: Option<&[usize]>,
        name: Option<&str>,
    ) -> Result<super::OverrideHandle> {
        self.check_rig(rig)?;
        let chains = match chains {
            None => None,
            Some(list) => {
                if let Some(&bad) = list.iter().find(|&&ci| ci >= rig.chains.len()) {
                    return Err(Error::InvalidParameter(format!(
                        "settings override: there is no chain {bad} (the rig has {})",
                        rig.chains.len()
                    )));
                }
                Some(list.iter().map(|&ci| ci as u16).collect())
            }
        };
        self.overrides.start(scale, timing, chains, name)
    }

    /// Stops a settings override: it blends out from where it is over `blend_out` seconds
    /// (0: at once) from the next frame. False when no override has the handle (it ended,
    /// was dropped, or is another character's).
    pub fn stop_settings_override(
        &mut self,
        handle: super::OverrideHandle,
        blend_out: f32,
    ) -> bool {
        self.overrides.stop(handle, blend_out)
    }

    /// Stops every settings override started with `name`; how many.
    pub fn stop_named_settings_override(&mut self, name: &str, blend_out: f32) -> usize {
        self.overrides.stop_named(name, blend_out)
    }

    /// Drops every settings override at once, acting or queued.
    pub fn clear_settings_overrides(&mut self) {
        self.overrides.clear();
    }

    /// Chain `ci`'s settings scales as the last frame ended (all 1 while no override
    /// acts): the product of the overrides on it, each blended by its envelope.
    /// (`fixed` chains on their own clock, see [`ChainState::start_settings_override`].)
    pub fn settings_scale(&self, rig: &ChainRig, ci: usize) -> super::SettingsScale {
        if self.overrides.active() && ci < self.alpha.len() && ci < rig.chains.len() {
            let fixed = rig.chains[ci].settings.mode == TimeMode::Fixed;
            self.overrides.scale(ci, 0.0, fixed)
        } else {
            super::SettingsScale::ONE
        }
    }

    /// How many settings overrides act (as the last frame ended).
    pub fn settings_override_count(&self) -> usize {
        self.overrides.len()
    }

    /// Sets the alpha of chain `ci` at run time, 0..=1 (multiplies its `alpha`: 0 shows
    /// the animated pose, 1 the simulated one; the chain keeps simulating). Errors on a
    /// chain past the last or an alpha outside 0..=1.
    pub fn set_alpha(&mut self, ci: usize, alpha: f32) -> Result<()> {
        if !(0.0..=1.0).contains(&alpha) {
            return Err(Error::InvalidParameter(format!(
                "alpha {alpha} is outside 0..=1"
            )));
        }
        let n = self.alpha.len();
        let slot = self.alpha.get_mut(ci).ok_or_else(|| {
            Error::InvalidParameter(format!("chain {ci} does not exist ({n} chains)"))
        })?;
        *slot = alpha;
        Ok(())
    }

    /// The run-time alpha of chain `ci` (1 unless set), or `None` past the last chain.
    pub fn alpha(&self, ci: usize) -> Option<f32> {
        self.alpha.get(ci).copied()
    }

    fn check_rig(&self, rig: &ChainRig) -> Result<()> {
        if self.pos.len() != rig.point_count() || self.alpha.len() != rig.chains.len() {
            return Err(Error::InvalidParameter(
                "chain state was made for another chain rig".into(),
            ));
        }
        Ok(())
    }

    /// The bridge points on the bone constraints (`bone_constraint_subdivision_count`) as
    /// the last frame left them (in `fixed` mode, its output step's), model space;
    /// [`ChainRig::bridge`] says where each lies.
    pub fn bridge_positions(&self) -> &[Vec3] {
        &self.bridge_out
    }

    /// The simulated point positions of the last frame's output, model space.
    pub fn output_positions(&self) -> &[Vec3] {
        &self.out
    }

    /// The animated target positions of the last frame, model space (as sync bones
    /// moved them, where the rig has any).
    pub fn target_positions(&self) -> &[Vec3] {
        &self.targets
    }

    /// Colliders as placed for the last frame, model space.
    pub fn placed_colliders(&self) -> &[PlacedCollider] {
        &self.colliders
    }

    /// How many resets a teleport (or a non-finite result) caused so far.
    pub fn teleport_count(&self) -> u64 {
        self.teleports + self.lanes.iter().map(ChainLanes::teleports).sum::<u64>()
    }
}

/// Chain `ci`'s wind generator for a fresh character.
pub(crate) fn chain_rng(rig: &ChainRig, ci: usize) -> SplitMix64 {
    SplitMix64::new(rig.chains[ci].settings.wind.seed ^ (ci as u64) << 32)
}

/// One frame of every chain of a character.
///
/// Reads the animated pose (`locals` and the `models` computed from them) and the
/// character's world transform; writes simulated rotations back into `locals` and
/// recomputes `models`.
#[derive(Debug)]
pub struct ChainJob<'a> {
    /// The skeleton the rig was compiled for.
    pub skeleton: &'a Skeleton,
    /// The compiled rig.
    pub rig: &'a ChainRig,
    /// The character's state.
    pub state: &'a mut ChainState,
    /// The character's world transform this frame.
    pub component: Transform,
    /// Frame time, seconds (finite, ≥ 0).
    pub dt: f32,
    /// In: animated local transforms. Out: with simulated rotations.
    pub locals: &'a mut [Transform],
    /// In: animated model transforms. Out: recomputed from the new locals.
    pub models: &'a mut [Transform],
    /// The world the chains with `world_collision` keep out of (world space), if any.
    pub level: Option<&'a Level>,
}

impl ChainJob<'_> {
    /// Checks sizes and that the inputs are finite.
    pub fn validate(&self) -> Result<()> {
        let n = self.skeleton.len();
        if self.rig.joint_count() != n {
            return Err(Error::LengthMismatch {
                what: "rig joints",
                expected: n,
                got: self.rig.joint_count(),
            });
        }
        for (what, got) in [("locals", self.locals.len()), ("models", self.models.len())] {
            if got != n {
                return Err(Error::LengthMismatch {
                    what,
                    expected: n,
                    got,
                });
            }
        }
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(Error::InvalidTimeStep(self.dt));
        }
        // A state made for another rig would be read out of its bounds.
        let state = &*self.state;
        let fits = state.pos.len() == self.rig.point_count()
            && state.accumulator.len() == self.rig.chains.len()
            && state.colliders.len() == self.rig.colliders.len() + state.shared.len()
            && state.lanes.len() == self.rig.lane_groups.len()
            && state.lambda.len() == self.rig.constraints.list.len()
            && state.bridge_pos.len() == self.rig.constraints.bridges.len()
            && state.feedback.len()
                == if self.rig.constraints.bridges.is_empty() {
                    0
                } else {
                    self.rig.point_count()
                }
            && state.alpha.len() == self.rig.chains.len()
            && state.base_now.len() == self.rig.chains.len()
            && state.forces.fits(self.rig)
            && state.animated.len()
                == if self.rig.syncs.is_empty() {
                    0
                } else {
                    self.rig.point_count()
                }
            && state
                .lanes
                .iter()
                .zip(&self.rig.lane_groups)
                .all(|(l, g)| l.fits(g));
        if !fits {
            return Err(Error::InvalidParameter(
                "chain state was made for another chain rig".into(),
            ));
        }
        if !self.component.is_finite() {
            return Err(Error::NonFinite("character transform".into()));
        }
        let first_bad = || self.models.iter().position(|m| !m.is_finite());
        if let Some(i) = (!crate::math::all_finite(self.models))
            .then(first_bad)
            .flatten()
        {
            return Err(Error::NonFinite(format!(
                "animated pose of joint '{}'",
                self.skeleton.name(i)
            )));
        }
        Ok(())
    }

    /// Validates, then runs the frame. Never allocates.
    pub fn run(self) -> Result<()> {
        self.validate()?;
        let ChainJob {
            skeleton,
            rig,
            state,
            component,
            dt,
            locals,
            models,
            level,
        } = self;
        // Timed settings overrides: this frame's taken in, the scaled settings on while
        // any acts.
        let overridden = state.overrides.advance(dt);
        state.params.set_active(rig, overridden);
        // External forces, run-time alphas and settings overrides are stepped on the
        // scalar path only (the lanes give the same bits without them).
        let lanes = state.simd != SimdUse::Scalar
            && !rig.lane_groups.is_empty()
            && !overridden
            && !state.forces.any()
            && state
                .shared_lists
                .iter()
                .enumerate()
                .all(|(ci, l)| l.is_empty() || !rig.in_lane_group(ci))
            && state.alpha.iter().all(|&a| a == 1.0);
        if lanes != state.in_lanes {
            state.move_lanes(rig, lanes);
        }
        gather_targets(
            skeleton,
            rig,
            models,
            &mut state.targets,
            &mut state.normals,
            &mut state.colliders,
        );
        // The colliders shared with this character, into its space.
        let m = rig.colliders.len();
        for (placed, world) in state.colliders[m..].iter_mut().zip(&state.shared) {
            let t = &world.transform;
            *placed = PlacedCollider {
                shape: world.shape,
                transform: Transform::from_translation_rotation(
                    component.inverse_transform_point(t.translation),
                    (component.rotation.inverse() * t.rotation).normalize(),
                ),
            };
        }
        if state.shared_fresh {
            // No placement of last frame to sweep from.
            let (now, before) = (&state.colliders[m..], &mut state.prev_colliders[m..]);
            before.copy_from_slice(now);
            state.shared_fresh = false;
        }
        state.forces.gather_bones(rig, models);
        for (ci, chain) in rig.chains.iter().enumerate() {
            if let Some(b) = chain.base {
                state.base_now[ci] = models[b];
            }
        }
        if !rig.syncs.is_empty() {
            state.animated.copy_from_slice(&state.targets);
            // A chain that starts again this frame has no simulated points yet: its
            // distance attenuation measures from the targets.
            for ci in 0..rig.chains.len() {
                if state.needs_reset[ci] && rig.synced_chain[ci] {
                    for p in rig.chains[ci].points.clone() {
                        state.pos[p] = state.targets[p];
                    }
                }
            }
            super::sync::apply(
                &rig.syncs,
                &rig.parent,
                models,
                &state.animated,
                &state.pos,
                &mut state.targets,
            );
        }
        for (b, c) in state.bounds.iter_mut().zip(&state.colliders) {
            *b = c.bound_sphere();
        }
        state.step_placed_at.fill(f32::NAN);

        state.path.push(component, dt);
        // One broad-phase query for the whole character; away from all geometry the
        // chains ask the level nothing more.
        let level = level.filter(|level| near_character(rig, state, &component, level));
        // A chain's frame reads nothing of another chain's, except within a group of chains
        // joined by bone constraints, which runs as one when its first chain's turn comes;
        // the twin chains in lanes run after the others.
        for ci in 0..rig.chains.len() {
            if lanes && rig.in_lane_group(ci) {
                continue;
            }
            match rig.group_of(ci) {
                None => run_chain(rig, ci, state, &component, dt, level),
                Some(g) if rig.constraints.groups[g].chains[0] == ci => {
                    run_group(rig, g, state, &component, dt, level)
                }
                Some(_) => {}
            }
        }
        if lanes {
            let frame = LaneFrame {
                component,
                dt,
                isa: Isa::of(state.simd),
            };
            for (group, lanes) in rig.lane_groups.iter().zip(&mut state.lanes) {
                lanes.frame(
                    skeleton,
                    rig,
                    group,
                    &frame,
                    &state.targets,
                    &state.normals,
                    &state.colliders,
                    &mut state.out,
                );
            }
        }
        state.prev_targets.copy_from_slice(&state.targets);
        state.prev_normals.copy_from_slice(&state.normals);
        state.prev_colliders.copy_from_slice(&state.colliders);
        state.prev_component = component;
        state.forces.end_frame();
        state.base_prev.copy_from_slice(&state.base_now);

        if lanes {
            for (group, lanes) in rig.lane_groups.iter().zip(&state.lanes) {
                lanes.write_back(
                    group,
                    locals,
                    models,
                    &mut state.turned,
                    Isa::of(state.simd),
                );
            }
        }
        write_back(
            skeleton,
            rig,
            if rig.syncs.is_empty() {
                &state.targets
            } else {
                &state.animated
            },
            &state.out,
            locals,
            models,
            lanes,
        );
        crate::pose::LocalToModelJob {
            skeleton,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }
}

/// Animated targets, planar normals (of the chains with a planar constraint) and placed
/// colliders from the animated model pose.
pub(crate) fn gather_targets(
    sk: &Skeleton,
    rig: &ChainRig,
    models: &[Transform],
    targets: &mut [Vec3],
    normals: &mut [Vec3],
    colliders: &mut [PlacedCollider],
) {
    for (p, axis) in rig.points_and_planar_axes() {
        let j = rig.joint[p];
        let parent = rig.real_parent[p];
        if rig.is_inter(p) {
            // Placed below, once both ends are.
        } else if j == VIRTUAL {
            let leaf = rig.joint[parent as usize] as usize;
            let from = sk.parent(leaf).map(|q| models[q].translation);
            let dir = match from {
                Some(f) => normalize_or(
                    models[leaf].translation - f,
                    models[leaf].rotation * Vec3::Y,
                ),
                None => models[leaf].rotation * Vec3::Y,
            };
            targets[p] = models[leaf].translation + dir * rig.dummy_length[p];
        } else {
            targets[p] = models[j as usize].translation;
        }
        // The normals only where a planar constraint reads them (the others keep what
        // they hold, never read).
        if let (true, Some(axis)) = (parent != NONE, axis) {
            let pj = rig.joint[parent as usize] as usize;
            normals[p] = models[pj].rotation * axis;
        }
    }
    // Points between bones: on their segment between its two ends (KawaiiPhysics 1.21's
    // `UpdateInterBoneDummyPose`, a second pass).
    if rig.subdivided {
        for p in 0..rig.point_count() {
            if rig.is_inter(p) {
                let (a, b) = (rig.real_parent[p] as usize, rig.inter_end[p] as usize);
                targets[p] = targets[a].lerp(targets[b], rig.inter_alpha[p]);
            }
        }
    }
    place_colliders(rig, models, colliders);
}

/// The rig's colliders placed on the model pose `models`.
pub(crate) fn place_colliders(
    rig: &ChainRig,
    models: &[Transform],
    colliders: &mut [PlacedCollider],
) {
    for (placed, c) in colliders.iter_mut().zip(&rig.colliders) {
        *placed = c.place(models, None);
    }
}

/// Starts chain `ci` again from the animated pose, with its warm-up steps (`warmup`) or
/// without (a group warms its chains up together).
fn reset_chain(
    rig: &ChainRig,
    ci: usize,
    state: &mut ChainState,
    component: &Transform,
    warmup: bool,
) {
    for p in rig.chains[ci].points.clone() {
        state.pos[p] = state.targets[p];
        state.prev[p] = state.targets[p];
        state.dev[p] = Vec3::ZERO;
        state.dev_before[p] = Vec3::ZERO;
        state.prev_targets[p] = state.targets[p];
        state.prev_normals[p] = state.normals[p];
    }
    // The colliders' last placement is every chain's: a chain that starts again does not
    // change how the others see the colliders move this frame (it takes no step of its
    // own this frame, and the frame's end places them for all).
    state.accumulator[ci] = 0.0;
    state.last_step_component[ci] = *component;
    state.base_prev[ci] = state.base_now[ci];
    state.last_step_base[ci] = state.base_now[ci];
    let s = &rig.chains[ci].settings;
    let h = 1.0 / s.target_framerate;
    state.dt_old[ci] = h;
    // Warm-up: settle in place with the current targets and no character motion.
    for _ in 0..if warmup { s.warmup_steps } else { 0 } {
        let input = StepInput {
            targets: &state.targets,
            normals: &state.normals,
            colliders: &state.colliders,
            bounds: &state.bounds,
            move_cs: Vec3::ZERO,
            rotate_cs: Quat::IDENTITY,
            gravity_cs: gravity_cs(s, component),
            wind_cs: wind_cs(s, component),
            dt: h,
            dt_old: h,
            part: 1.0,
            fixed: accelerates(s),
            world: None,
            push: &[],
            accel: &[],
            base: None,
            params: state.params.view(rig),
            list: list_of(rig, &state.shared_lists, ci),
            every: every_of(rig, &state.every),
        };
        step_chain(
            rig,
            ci,
            &input,
            &mut state.pos,
            &mut state.prev,
            &mut state.rng[ci],
        );
    }
    for p in rig.chains[ci].points.clone() {
        state.dev[p] = state.pos[p] - state.targets[p];
        state.dev_before[p] = state.dev[p];
    }
    state.needs_reset[ci] = false;
}

pub(crate) fn gravity_cs(s: &super::ChainSettings, component: &Transform) -> Vec3 {
    if s.gravity_in_world {
        component.rotation.inverse() * s.gravity
    } else {
        s.gravity
    }
}

pub(crate) fn wind_cs(s: &super::ChainSettings, component: &Transform) -> Vec3 {
    component.rotation.inverse() * normalize_or(s.wind.direction, Vec3::ZERO)
}

/// Carries chain `ci`'s points into its simulation space for a step over which the
/// character moves `from → to` (world transforms), and returns what the step reads of the
/// character's motion: `component` space, the motion as inertia (its translation scaled by
/// `skel_comp_move_scale`); `world` space, nothing (the points were carried to keep their
/// world place); `base_bone` space, the points carried with the base bone from its last
/// step's transform to `base_to`, then the motion as in `component`, with both base
/// transforms (the turn acts on where the points were).
fn space_step(
    rig: &ChainRig,
    ci: usize,
    state: &mut ChainState,
    from: Transform,
    to: Transform,
    base_to: Transform,
) -> SpaceIn {
    let ChainState {
        pos,
        prev,
        last_step_base,
        ..
    } = state;
    carry(
        rig,
        ci,
        pos,
        prev,
        &mut last_step_base[ci],
        from,
        to,
        base_to,
    )
}

/// [`space_step`] on the points `pos`/`prev` with the base bone's last step transform
/// `last_base` (fixed mode's output step carries copies).
#[allow(clippy::too_many_arguments)]
fn carry(
    rig: &ChainRig,
    ci: usize,
    pos: &mut [Vec3],
    prev: &mut [Vec3],
    last_base: &mut Transform,
    from: Transform,
    to: Transform,
    base_to: Transform,
) -> SpaceIn {
    let chain = &rig.chains[ci];
    let s = &chain.settings;
    let (move_cs, rotate_cs) = motion_cs(&from, &to);
    match s.simulation_space {
        super::SimulationSpace::Component => (move_cs * s.skel_comp_move_scale, rotate_cs, None),
        super::SimulationSpace::World => {
            for p in chain.points.clone() {
                pos[p] = rotate_cs * pos[p] + move_cs;
                prev[p] = rotate_cs * prev[p] + move_cs;
            }
            (Vec3::ZERO, Quat::IDENTITY, None)
        }
        super::SimulationSpace::BaseBone => {
            let from_base = *last_base;
            for p in chain.points.clone() {
                pos[p] = base_to.transform_point(from_base.inverse_transform_point(pos[p]));
                prev[p] = base_to.transform_point(from_base.inverse_transform_point(prev[p]));
            }
            *last_base = base_to;
            (
                move_cs * s.skel_comp_move_scale,
                rotate_cs,
                Some((from_base, base_to)),
            )
        }
    }
}

/// Character motion from `a` to `b`, as seen from `b`'s space.
pub(crate) fn motion_cs(a: &Transform, b: &Transform) -> (Vec3, Quat) {
    let inv = b.rotation.inverse();
    (
        inv * (a.translation - b.translation),
        (inv * a.rotation).normalize(),
    )
}

/// How far any point of chain `ci` (with its radius) can be from the chain's root: its
/// bone lengths in `targets` and radii, summed.
fn chain_reach(rig: &ChainRig, ci: usize, targets: &[Vec3], radius_scale: f32) -> f32 {
    let mut reach = 0.0f32;
    for p in rig.chains[ci].points.clone() {
        let parent = rig.parent[p];
        if parent != NONE {
            reach +=
                (targets[p] - targets[parent as usize]).length() + rig.radius[p] * radius_scale;
        }
    }
    reach
}

/// Whether any level geometry lies within reach of a chain that collides with the world,
/// anywhere along this frame: one BVH query around every such chain's root at the last
/// frame's end and now, grown by its reach (and a quarter of the root's travel, for a
/// step path that bends away from the straight line).
fn near_character(
    rig: &ChainRig,
    state: &ChainState,
    component: &Transform,
    level: &Level,
) -> bool {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for (ci, chain) in rig.chains.iter().enumerate() {
        if !chain.settings.world_collision {
            continue;
        }
        let root = chain.points.start;
        let a = state.prev_component.transform_point(state.pos[root]);
        let b = component.transform_point(state.targets[root]);
        let margin = chain_reach(rig, ci, &state.targets, state.params.radius_scale(ci))
            + 0.25 * (b - a).length()
            + 1e-2;
        lo = lo.min(a.min(b) - margin);
        hi = hi.max(a.max(b) + margin);
    }
    lo.x <= hi.x && level.touches_aabb(lo, hi)
}

/// The world as this chain's step from `from` to `to` sees it: `None` without a level,
/// without `world_collision`, or when no geometry is within the chain's reach.
#[allow(clippy::too_many_arguments)]
fn world_for<'a>(
    rig: &ChainRig,
    ci: usize,
    level: Option<&'a Level>,
    radius_scale: f32,
    pos: &[Vec3],
    targets: &[Vec3],
    from: &Transform,
    to: &Transform,
) -> Option<WorldContact<'a>> {
    let chain = &rig.chains[ci];
    let level = level.filter(|_| chain.settings.world_collision)?;
    let root = chain.points.start;
    let reach = chain_reach(rig, ci, targets, radius_scale);
    let world = WorldContact {
        level,
        from: *from,
        to: *to,
    };
    world
        .near(pos[root], targets[root], reach + 1e-3)
        .then_some(world)
}

fn run_chain(
    rig: &ChainRig,
    ci: usize,
    state: &mut ChainState,
    component: &Transform,
    dt: f32,
    level: Option<&Level>,
) {
    let s = &rig.chains[ci].settings;
    let points = rig.chains[ci].points.clone();
    scale_settings(rig, &[ci], state, 0.0);
    // Teleport detection on the character's own motion this frame.
    if !state.needs_reset[ci] && teleported(s, state, component) {
        state.needs_reset[ci] = true;
        state.teleports += 1;
    }
    let mut reset = state.needs_reset[ci];
    if reset {
        reset_chain(rig, ci, state, component, true);
    } else {
        match s.mode {
            TimeMode::Classic => {
                let dt = dt.min(s.max_delta_time);
                // The points carried into this frame's simulation space, step or not.
                let (move_cs, rotate_cs, base) = space_step(
                    rig,
                    ci,
                    state,
                    state.prev_component,
                    *component,
                    state.base_now[ci],
                );
                if dt > 0.0 {
                    let forced = state.forces.prepare(
                        rig,
                        ci,
                        dt,
                        1.0,
                        component,
                        &state.pos,
                        &state.targets,
                    );
                    let world = world_for(
                        rig,
                        ci,
                        level,
                        state.params.radius_scale(ci),
                        &state.pos,
                        &state.targets,
                        &state.prev_component,
                        component,
                    );
                    let input = StepInput {
                        targets: &state.targets,
                        normals: &state.normals,
                        colliders: &state.colliders,
                        bounds: &state.bounds,
                        move_cs,
                        rotate_cs,
                        gravity_cs: gravity_cs(s, component),
                        wind_cs: wind_cs(s, component),
                        dt,
                        dt_old: state.dt_old[ci],
                        part: 1.0,
                        fixed: false,
                        world,
                        push: if forced { &state.forces.push } else { &[] },
                        accel: &state.forces.accel,
                        base,
                        params: state.params.view(rig),
                        list: list_of(rig, &state.shared_lists, ci),
                        every: every_of(rig, &state.every),
                    };
                    step_chain(
                        rig,
                        ci,
                        &input,
                        &mut state.pos,
                        &mut state.prev,
                        &mut state.rng[ci],
                    );
                    state.dt_old[ci] = dt;
                }
                for p in points.clone() {
                    state.dev[p] = state.pos[p] - state.targets[p];
                    state.dev_before[p] = state.dev[p];
                }
            }
            TimeMode::Fixed => run_fixed(rig, ci, state, dt, level),
            TimeMode::Kawaii => {
                let alone = GroupRef {
                    chains: std::slice::from_ref(&ci),
                    constraints: 0..0,
                    bridges: 0..0,
                };
                run_kawaii(rig, alone, state, component, dt, level);
            }
        }
    }
    // Guard: never let a non-finite value out; start again from the pose instead.
    if points.clone().any(|p| !state.pos[p].is_finite()) {
        state.teleports += 1;
        reset_chain(rig, ci, state, component, true);
        reset = true;
    }
    if s.mode == TimeMode::Fixed {
        output_step(rig, ci, state, component, level);
    }
    output_chain(rig, ci, state, component, level, reset);
}

/// The share of a fixed step under which the time left over after a frame's steps
/// counts as none (the tolerance with which [`fixed_steps`] counts them): that frame
/// ends on its last step.
pub(crate) const ON_STEP: f32 = 1e-4;

/// Chain `ci`'s collider list: the rig's, with the shared colliders when it uses them.
fn list_of<'a>(rig: &'a ChainRig, lists: &'a [Vec<usize>], ci: usize) -> &'a [usize] {
    match lists.get(ci) {
        Some(l) if !l.is_empty() => l,
        _ => &rig.chains[ci].colliders,
    }
}

/// Every collider's index (the bridge points collide with all): the rig's, and the shared
/// ones when any are set.
fn every_of<'a>(rig: &'a ChainRig, every: &'a [usize]) -> &'a [usize] {
    if every.is_empty() {
        &rig.constraints.all_colliders
    } else {
        every
    }
}

/// Writes the settings of `chains` as the timed overrides scale them `back` seconds
/// before the frame's end (nothing while none acts).
fn scale_settings(rig: &ChainRig, chains: &[usize], state: &mut ChainState, back: f32) {
    if state.params.active {
        for &ci in chains {
            let fixed = rig.chains[ci].settings.mode == TimeMode::Fixed;
            let scale = state.overrides.scale(ci, back, fixed);
            state.params.write(rig, ci, &scale);
        }
    }
}

/// Fixed mode's output points of chain `ci` in `out` (issue 63): the chain as it is at
/// the frame's end. A frame that ends on a step outputs that step's points. Between
/// steps, the output is the part `a` of one more step that the time left over makes
/// (the accumulator over the step's length), from the last step's state, on this frame's
/// targets, colliders, character transform and world, with the external forces of the
/// last step: velocity, gravity, pull and push each move the points by `a` of what a
/// step would (`StepInput::part`; a step of `a·h` would give gravity `a²` and the pull
/// `1 − (1 − k)^a`, which kink the output where steps land: measured rougher at
/// 144 Hz); contacts, limits and lengths as in a step. Its points go to `out` and
/// nothing of it is kept (the next frame steps on from the last whole step).
/// Continuous: `a → 0` gives the last step's points, `a → 1` the next step's. Its wind
/// draws from a copy of the chain's generator.
fn output_step(
    rig: &ChainRig,
    ci: usize,
    state: &mut ChainState,
    component: &Transform,
    level: Option<&Level>,
) {
    let s = &rig.chains[ci].settings;
    let points = rig.chains[ci].points.clone();
    state.out[points.clone()].copy_from_slice(&state.pos[points.clone()]);
    let h = 1.0 / s.target_framerate;
    let left = state.accumulator[ci];
    if left <= ON_STEP * h {
        return;
    }
    scale_settings(rig, &[ci], state, 0.0);
    state.keep_prev[points.clone()].copy_from_slice(&state.prev[points]);
    let from = state.last_step_component[ci];
    let mut base = state.last_step_base[ci];
    let (move_cs, rotate_cs, base) = carry(
        rig,
        ci,
        &mut state.out,
        &mut state.keep_prev,
        &mut base,
        from,
        *component,
        state.base_now[ci],
    );
    let world = world_for(
        rig,
        ci,
        level,
        state.params.radius_scale(ci),
        &state.out,
        &state.targets,
        &from,
        component,
    );
    let input = StepInput {
        targets: &state.targets,
        normals: &state.normals,
        colliders: &state.colliders,
        bounds: &state.bounds,
        move_cs,
        rotate_cs,
        gravity_cs: gravity_cs(s, component),
        wind_cs: wind_cs(s, component),
        dt: h,
        dt_old: h,
        part: left / h,
        fixed: true,
        world,
        push: if state.forces.reaches(ci) {
            &state.forces.push
        } else {
            &[]
        },
        accel: &state.forces.accel,
        base,
        params: state.params.view(rig),
        list: list_of(rig, &state.shared_lists, ci),
        every: every_of(rig, &state.every),
    };
    let mut rng = state.rng[ci];
    step_chain(
        rig,
        ci,
        &input,
        &mut state.out,
        &mut state.keep_prev,
        &mut rng,
    );
}

/// [`output_step`] for bone-constraint group `group` (one clock: its lead chain's):
/// the group's chains step on together (with their bridge points, in copies). Returns
/// whether an output step ran.
fn output_step_group(
    rig: &ChainRig,
    group: &ChainGroup,
    state: &mut ChainState,
    component: &Transform,
    level: Option<&Level>,
) -> bool {
    let lead = group.chains[0];
    for &ci in &group.chains {
        let points = rig.chains[ci].points.clone();
        state.out[points.clone()].copy_from_slice(&state.pos[points]);
    }
    let h = 1.0 / rig.chains[lead].settings.target_framerate;
    let left = state.accumulator[lead];
    if left <= ON_STEP * h {
        return false;
    }
    scale_settings(rig, &group.chains, state, 0.0);
    let from = state.last_step_component[lead];
    for &ci in &group.chains {
        let points = rig.chains[ci].points.clone();
        state.keep_prev[points.clone()].copy_from_slice(&state.prev[points]);
        state.world_near[ci] = world_for(
            rig,
            ci,
            level,
            state.params.radius_scale(ci),
            &state.out,
            &state.targets,
            &from,
            component,
        )
        .is_some();
    }
    for &ci in &group.chains {
        let mut base = state.last_step_base[ci];
        state.space_in[ci] = carry(
            rig,
            ci,
            &mut state.out,
            &mut state.keep_prev,
            &mut base,
            from,
            *component,
            state.base_now[ci],
        );
    }
    state.keep_rng.copy_from_slice(&state.rng);
    state.keep_bridge_pos.copy_from_slice(&state.bridge_pos);
    state.keep_bridge_prev.copy_from_slice(&state.bridge_prev);
    let ChainState {
        out,
        keep_prev,
        keep_rng,
        keep_bridge_pos,
        keep_bridge_prev,
        feedback,
        lambda,
        targets,
        normals,
        colliders,
        bounds,
        world_near,
        forces,
        space_in,
        params,
        shared_lists,
        every,
        ..
    } = &mut *state;
    let frame = GroupFrame {
        targets,
        normals,
        colliders,
        bounds,
        space_in,
        world_near,
        forces,
        level,
        from,
        component,
        params: params.view(rig),
        lists: shared_lists,
        every,
    };
    let part = left / h;
    let input_of = |ci: usize| StepInput {
        part,
        ..frame.input(rig, ci, h, h, true, None)
    };
    step_group(
        rig,
        group.into(),
        &input_of,
        out,
        keep_prev,
        keep_rng,
        lambda,
        &mut Bridges {
            pos: keep_bridge_pos,
            prev: keep_bridge_prev,
            feedback,
        },
    );
    true
}

/// Whether the character's motion this frame crosses chain settings `s`' teleport
/// thresholds.
fn teleported(s: &super::ChainSettings, state: &ChainState, component: &Transform) -> bool {
    let moved = (component.translation - state.prev_component.translation).length();
    let turned = slerp_angle(state.prev_component.rotation, component.rotation).to_degrees();
    (s.teleport_distance > 0.0 && moved > s.teleport_distance)
        || (s.teleport_rotation > 0.0 && turned > s.teleport_rotation)
}

/// Chain `ci`'s output: the animated pose plus the deviation, blended by alpha, with
/// bone lengths restored from the root down and this frame's colliders kept. `reset`:
/// the chain started again this frame (from the pose, which may be in a collider).
fn output_chain(
    rig: &ChainRig,
    ci: usize,
    state: &mut ChainState,
    component: &Transform,
    level: Option<&Level>,
    reset: bool,
) {
    let s = &rig.chains[ci].settings;
    let points = rig.chains[ci].points.clone();
    let alpha = s.alpha * state.alpha[ci];
    if s.mode == TimeMode::Fixed {
        // `out` holds the points at the frame's end ([`output_step`]): kept out of this
        // frame's colliders and at their bone lengths by the step that put them there
        // (unless the chain started again from its pose this frame).
        if alpha == 1.0 && !reset {
            return;
        }
        for p in points.clone() {
            state.dev[p] = state.out[p] - state.targets[p];
            state.dev_before[p] = state.dev[p];
        }
    }
    // Output: the animated pose plus the deviation, blended by alpha, with bone lengths
    // restored from the root down (`dev_before` is `dev`: the lerp at 1 keeps the bits
    // the frame's old interpolation gave).
    let w = 1.0;
    // The world, only when geometry is within the chain's reach this frame (one BVH
    // query, as in the steps).
    let world = world_for(
        rig,
        ci,
        level,
        state.params.radius_scale(ci),
        &state.targets,
        &state.targets,
        component,
        component,
    )
    .map(|w| w.level);
    let params = state.params.view(rig);
    for p in points {
        let t = state.targets[p];
        let dev = state.dev_before[p].lerp(state.dev[p], w) * alpha;
        let parent = rig.parent[p];
        state.out[p] = if parent == NONE {
            t
        } else {
            let pp = parent as usize;
            let anim = t - state.targets[pp];
            let restore = |x: Vec3| {
                state.out[pp]
                    + normalize_or(x - state.out[pp], normalize_or(anim, Vec3::Y)) * anim.length()
            };
            // The interpolated output also respects this frame's colliders.
            let mut x = restore(t + dev);
            let r = params.radius[p];
            // Broad phase (as in the step): every pass starts from a point on the sphere of
            // the bone's length about the parent's output.
            let list = list_of(rig, &state.shared_lists, ci);
            let length = anim.length();
            let near = NearSet::of(
                list,
                &state.bounds,
                state.out[pp] - length,
                state.out[pp] + length,
                r,
            );
            let collide = |x: Vec3| {
                let mut x = near.resolve(list, &state.colliders, x, None, r);
                if let Some(level) = world {
                    let w = component.transform_point(x);
                    let out = push_out(level, w, r);
                    if out != w {
                        x = component.inverse_transform_point(out);
                    }
                }
                x
            };
            for pass in 0..3 {
                let y = collide(x);
                if y == x {
                    break;
                }
                x = if pass < 2 { restore(y) } else { y };
            }
            x
        };
    }
}

pub(crate) fn slerp_angle(a: Quat, b: Quat) -> f32 {
    let d = a.dot(b).abs().min(1.0);
    2.0 * d.acos()
}

/// Chain `ci`'s targets, normals and colliders for a fixed step ending at share `w` of
/// the frame (a collider shared with another chain stepping at the same time is placed
/// once).
fn place_step(rig: &ChainRig, ci: usize, state: &mut ChainState, w: f32) {
    place_targets(rig, ci, state, w);
    let lists = std::mem::take(&mut state.shared_lists);
    place_step_colliders(list_of(rig, &lists, ci), state, w);
    state.shared_lists = lists;
}

/// The colliders `list` placed `w` of the way from last frame's to this frame's (each once
/// per step time).
fn place_step_colliders(list: &[usize], state: &mut ChainState, w: f32) {
    for &c in list {
        if state.step_placed_at[c].to_bits() != w.to_bits() {
            state.step_colliders[c] = state.prev_colliders[c].lerp(&state.colliders[c], w);
            state.step_bounds[c] = state.step_colliders[c].bound_sphere();
            state.step_placed_at[c] = w;
        }
    }
}

/// Whether a step adds gravity as an acceleration (`g·dt²`): `fixed` mode always;
/// `kawaii` mode unless the rig asks for KawaiiPhysics' legacy `½·g·dt²`
/// (`classic_gravity = "half_dt_squared"`; 1.21's default is the acceleration);
/// `classic` mode by `classic_gravity`.
fn accelerates(s: &super::ChainSettings) -> bool {
    match s.mode {
        TimeMode::Fixed => true,
        TimeMode::Kawaii => s.classic_gravity != super::ClassicGravity::HalfDtSquared,
        TimeMode::Classic => false,
    }
}

/// A `kawaii`-mode frame of a group of chains (or of one chain alone): KawaiiPhysics
/// 1.21's `SimulateModifyBones` with fixed substepping, as its code runs (f32):
///
/// - the step is `1 / target_framerate`; the time to step is the accumulator plus the
///   frame (at least 1e-4 s: `KINDA_SMALL_NUMBER`), capped at `max_substeps` steps, the
///   excess dropped; the whole steps in it run, the rest carries to the next frame;
/// - substep `k` of `n` steps toward the pose at `k / n` of the way from last frame's to
///   this frame's (positions lerped, planar normals nlerped), with this frame's colliders;
/// - each substep takes `step / time to step` of the character's motion since the
///   place the chain last consumed (`last_step_component`), which then advances by the
///   share of that time consumed or dropped (lerp, slerp): motion not yet stepped
///   reaches the next frame that steps;
/// - the steps run 1.20/1.21's phase order ([`step_group`]): every point integrated
///   (velocity over the last step, damping, gravity `g·dt²`, the share of motion, the
///   pull with the exponent `target_framerate · step`), constraints (compliance over
///   the step²), collisions, constraints, limits and bone lengths;
/// - no output interpolation: the points are where the last substep left them.
fn run_kawaii(
    rig: &ChainRig,
    group: GroupRef,
    state: &mut ChainState,
    component: &Transform,
    dt: f32,
    level: Option<&Level>,
) {
    let lead = group.chains[0];
    let s = &rig.chains[lead].settings;
    let h = 1.0 / s.target_framerate;
    let raw = (state.accumulator[lead] + dt).max(1e-4);
    let mut accumulated = raw.min(s.max_substeps as f32 * h);
    let dropped = raw - accumulated;
    let steps = (accumulated / h).floor() as u32;
    accumulated -= steps as f32 * h;
    let share = h / raw;
    let consumed = ((steps as f32 * h + dropped) / raw).clamp(0.0, 1.0);
    let from = state.last_step_component[lead];
    for &ci in group.chains {
        state.accumulator[ci] = accumulated;
        // The whole frame's motion (carried into this frame's simulation space), shared
        // out below.
        state.space_in[ci] = space_step(rig, ci, state, from, *component, state.base_now[ci]);
    }
    for k in 1..=steps {
        let alpha = k as f32 / steps as f32;
        for &ci in group.chains {
            // This frame's colliders, not interpolated ones: as 1.21 places them once a frame.
            place_targets(rig, ci, state, alpha);
            state.world_near[ci] = world_for(
                rig,
                ci,
                level,
                state.params.radius_scale(ci),
                &state.pos,
                &state.step_targets,
                &from,
                component,
            )
            .is_some();
            state.forces.prepare(
                rig,
                ci,
                h,
                alpha,
                component,
                &state.pos,
                &state.step_targets,
            );
        }
        let ChainState {
            pos,
            prev,
            rng,
            lambda,
            bridge_pos,
            bridge_prev,
            feedback,
            step_targets,
            step_normals,
            colliders,
            bounds,
            world_near,
            forces,
            space_in,
            params,
            shared_lists,
            every,
            ..
        } = &mut *state;
        let frame = GroupFrame {
            targets: step_targets,
            normals: step_normals,
            colliders,
            bounds,
            space_in,
            world_near,
            forces,
            level,
            from,
            component,
            params: params.view(rig),
            lists: shared_lists,
            every,
        };
        let input_of = |ci: usize| {
            let s = &rig.chains[ci].settings;
            frame.input(rig, ci, h, h, accelerates(s), Some(share))
        };
        step_group(
            rig,
            group.clone(),
            &input_of,
            pos,
            prev,
            rng,
            lambda,
            &mut Bridges {
                pos: bridge_pos,
                prev: bridge_prev,
                feedback,
            },
        );
    }
    let advanced = if consumed >= 1.0 - 1e-4 {
        *component
    } else {
        Transform::new(
            from.translation.lerp(component.translation, consumed),
            from.rotation
                .slerp(component.rotation, consumed)
                .normalize(),
            from.scale.lerp(component.scale, consumed),
        )
    };
    for &ci in group.chains {
        state.dt_old[ci] = h;
        state.last_step_component[ci] = advanced;
        for p in rig.chains[ci].points.clone() {
            state.dev[p] = state.pos[p] - state.targets[p];
            state.dev_before[p] = state.dev[p];
        }
    }
}

/// Chain `ci`'s step targets and planar normals `w` of the way from last frame's to
/// this frame's.
fn place_targets(rig: &ChainRig, ci: usize, state: &mut ChainState, w: f32) {
    for p in rig.chains[ci].points.clone() {
        state.step_targets[p] = state.prev_targets[p].lerp(state.targets[p], w);
        state.step_normals[p] = normalize_or(
            state.prev_normals[p].lerp(state.normals[p], w),
            state.normals[p],
        );
    }
}

/// What the chains of a group step on this frame besides their own settings: the targets
/// and colliders, each chain's share of the character's motion, the world and the
/// forces. `classic` and `kawaii` frames both build their step inputs from it.
struct GroupFrame<'a> {
    targets: &'a [Vec3],
    normals: &'a [Vec3],
    colliders: &'a [PlacedCollider],
    bounds: &'a [Vec4],
    space_in: &'a [SpaceIn],
    world_near: &'a [bool],
    forces: &'a super::force::Forces,
    level: Option<&'a Level>,
    from: Transform,
    component: &'a Transform,
    params: super::overrides::Params<'a>,
    lists: &'a [Vec<usize>],
    every: &'a [usize],
}

impl<'a> GroupFrame<'a> {
    /// Chain `ci`'s step of `dt` after one of `dt_old`, gravity as an acceleration when
    /// `fixed`, taking `share` of the character's motion (`None`: all of it, untouched).
    fn input(
        &self,
        rig: &'a ChainRig,
        ci: usize,
        dt: f32,
        dt_old: f32,
        fixed: bool,
        share: Option<f32>,
    ) -> StepInput<'a> {
        let s = &rig.chains[ci].settings;
        let (mut move_cs, mut rotate_cs, base) = self.space_in[ci];
        if let Some(share) = share {
            move_cs *= share;
            rotate_cs = Quat::IDENTITY.slerp(rotate_cs, share).normalize();
        }
        let (from, to) = (self.from, *self.component);
        StepInput {
            targets: self.targets,
            normals: self.normals,
            colliders: self.colliders,
            bounds: self.bounds,
            move_cs,
            rotate_cs,
            gravity_cs: gravity_cs(s, self.component),
            wind_cs: wind_cs(s, self.component),
            dt,
            dt_old,
            part: 1.0,
            fixed,
            world: self
                .level
                .filter(|_| self.world_near[ci])
                .map(|level| WorldContact { level, from, to }),
            push: if self.forces.reaches(ci) {
                &self.forces.push
            } else {
                &[]
            },
            accel: &self.forces.accel,
            base,
            params: self.params,
            list: list_of(rig, self.lists, ci),
            every: every_of(rig, self.every),
        }
    }
}

/// The fixed steps of a frame of `dt` after `acc_old` seconds left over: how many, the
/// time they cover, and the time a hitch dropped.
fn fixed_steps(s: &super::ChainSettings, acc_old: f32, dt: f32) -> (u32, f32, f32) {
    let h = 1.0 / s.target_framerate;
    let mut total = acc_old + dt;
    let mut steps = (total / h + 1e-4).floor() as u32;
    if steps > s.max_steps_per_frame {
        // A hitch: drop the time we cannot afford, keep the most recent steps.
        total -= (steps - s.max_steps_per_frame) as f32 * h;
        steps = s.max_steps_per_frame;
    }
    (steps, total, acc_old + dt - total)
}

/// Where step `k` of a frame of `dt` ends between last frame (0) and this frame (1).
fn step_end(k: u32, h: f32, acc_old: f32, skipped: f32, dt: f32) -> f32 {
    let end = k as f32 * h - acc_old + skipped;
    if dt > 0.0 {
        (end / dt).clamp(0.0, 1.0)
    } else {
        1.0
    }
}

fn run_fixed(rig: &ChainRig, ci: usize, state: &mut ChainState, dt: f32, level: Option<&Level>) {
    let s = &rig.chains[ci].settings;
    let h = 1.0 / s.target_framerate;
    let acc_old = state.accumulator[ci];
    let (steps, total, skipped) = fixed_steps(s, acc_old, dt);
    for k in 1..=steps {
        let w = step_end(k, h, acc_old, skipped, dt);
        // Fixed steps read the overrides at their own time (frame-rate independent).
        scale_settings(rig, &[ci], state, (1.0 - w) * dt);
        place_step(rig, ci, state, w);
        let comp_b = state.path.at(w);
        let base_b = state.base_prev[ci].lerp(&state.base_now[ci], w);
        let (move_cs, rotate_cs, base) = space_step(
            rig,
            ci,
            state,
            state.last_step_component[ci],
            comp_b,
            base_b,
        );
        let forced = state
            .forces
            .prepare(rig, ci, h, w, &comp_b, &state.pos, &state.step_targets);
        let world = world_for(
            rig,
            ci,
            level,
            state.params.radius_scale(ci),
            &state.pos,
            &state.step_targets,
            &state.last_step_component[ci],
            &comp_b,
        );
        let input = StepInput {
            targets: &state.step_targets,
            normals: &state.step_normals,
            colliders: &state.step_colliders,
            bounds: &state.step_bounds,
            move_cs,
            rotate_cs,
            gravity_cs: gravity_cs(s, &comp_b),
            wind_cs: wind_cs(s, &comp_b),
            dt: h,
            dt_old: h,
            part: 1.0,
            fixed: true,
            world,
            push: if forced { &state.forces.push } else { &[] },
            accel: &state.forces.accel,
            base,
            params: state.params.view(rig),
            list: list_of(rig, &state.shared_lists, ci),
            every: every_of(rig, &state.every),
        };
        step_chain(
            rig,
            ci,
            &input,
            &mut state.pos,
            &mut state.prev,
            &mut state.rng[ci],
        );
        state.last_step_component[ci] = comp_b;
    }
    state.accumulator[ci] = (total - steps as f32 * h).max(0.0);
}

/// One frame of bone-constraint group `g`: its chains reset together, step together
/// ([`step_group`]) and are written out one by one.
fn run_group(
    rig: &ChainRig,
    g: usize,
    state: &mut ChainState,
    component: &Transform,
    dt: f32,
    level: Option<&Level>,
) {
    let group = &rig.constraints.groups[g];
    let lead = group.chains[0];
    let s = &rig.chains[lead].settings;
    scale_settings(rig, &group.chains, state, 0.0);
    let mut reset = group.chains.iter().any(|&ci| state.needs_reset[ci]);
    if !reset
        && group
            .chains
            .iter()
            .any(|&ci| teleported(&rig.chains[ci].settings, state, component))
    {
        state.teleports += 1;
        reset = true;
    }
    if reset {
        reset_group(rig, group, state, component);
    } else {
        match s.mode {
            TimeMode::Classic => {
                let dt = dt.min(s.max_delta_time);
                // The points carried into this frame's simulation space, step or not.
                for &ci in &group.chains {
                    state.space_in[ci] = space_step(
                        rig,
                        ci,
                        state,
                        state.prev_component,
                        *component,
                        state.base_now[ci],
                    );
                }
                if dt > 0.0 {
                    let from = state.prev_component;
                    for &ci in &group.chains {
                        state.world_near[ci] = world_for(
                            rig,
                            ci,
                            level,
                            state.params.radius_scale(ci),
                            &state.pos,
                            &state.targets,
                            &from,
                            component,
                        )
                        .is_some();
                    }
                    for &ci in &group.chains {
                        state.forces.prepare(
                            rig,
                            ci,
                            dt,
                            1.0,
                            component,
                            &state.pos,
                            &state.targets,
                        );
                    }
                    let ChainState {
                        pos,
                        prev,
                        rng,
                        lambda,
                        bridge_pos,
                        bridge_prev,
                        feedback,
                        targets,
                        normals,
                        colliders,
                        bounds,
                        dt_old,
                        world_near,
                        forces,
                        space_in,
                        params,
                        shared_lists,
                        every,
                        ..
                    } = &mut *state;
                    let frame = GroupFrame {
                        targets,
                        normals,
                        colliders,
                        bounds,
                        space_in,
                        world_near,
                        forces,
                        level,
                        from,
                        component,
                        params: params.view(rig),
                        lists: shared_lists,
                        every,
                    };
                    let input_of = |ci: usize| frame.input(rig, ci, dt, dt_old[ci], false, None);
                    step_group(
                        rig,
                        group.into(),
                        &input_of,
                        pos,
                        prev,
                        rng,
                        lambda,
                        &mut Bridges {
                            pos: bridge_pos,
                            prev: bridge_prev,
                            feedback,
                        },
                    );
                    group.chains.iter().for_each(|&ci| dt_old[ci] = dt);
                }
                for &ci in &group.chains {
                    for p in rig.chains[ci].points.clone() {
                        state.dev[p] = state.pos[p] - state.targets[p];
                        state.dev_before[p] = state.dev[p];
                    }
                }
            }
            TimeMode::Fixed => run_fixed_group(rig, group, state, dt, level),
            TimeMode::Kawaii => run_kawaii(rig, group.into(), state, component, dt, level),
        }
    }
    // Guard: never let a non-finite value out; start again from the pose instead.
    let bad = |ci: usize| {
        rig.chains[ci]
            .points
            .clone()
            .any(|p| !state.pos[p].is_finite())
    };
    if group.chains.iter().any(|&ci| bad(ci)) {
        state.teleports += 1;
        reset_group(rig, group, state, component);
        reset = true;
    }
    let stepped =
        s.mode == TimeMode::Fixed && output_step_group(rig, group, state, component, level);
    for i in group.bridges.clone() {
        state.bridge_out[i] = if stepped {
            state.keep_bridge_pos[i]
        } else {
            state.bridge_pos[i]
        };
    }
    for &ci in &group.chains {
        output_chain(rig, ci, state, component, level, reset);
    }
}

/// Starts a group's chains again from the animated pose and warms them up together.
fn reset_group(rig: &ChainRig, group: &ChainGroup, state: &mut ChainState, component: &Transform) {
    for &ci in &group.chains {
        reset_chain(rig, ci, state, component, false);
    }
    for i in group.bridges.clone() {
        let br = &rig.constraints.bridges[i];
        let at = state.targets[br.a as usize].lerp(state.targets[br.b as usize], br.alpha);
        state.bridge_pos[i] = at;
        state.bridge_prev[i] = at;
    }
    let s = &rig.chains[group.chains[0]].settings;
    let h = 1.0 / s.target_framerate;
    let fixed = accelerates(s);
    {
        let ChainState {
            pos,
            prev,
            rng,
            lambda,
            bridge_pos,
            bridge_prev,
            feedback,
            targets,
            normals,
            colliders,
            bounds,
            params,
            shared_lists,
            every,
            ..
        } = &mut *state;
        let params = params.view(rig);
        let input_of = |ci: usize| {
            let s = &rig.chains[ci].settings;
            StepInput {
                targets,
                normals,
                colliders,
                bounds,
                move_cs: Vec3::ZERO,
                rotate_cs: Quat::IDENTITY,
                gravity_cs: gravity_cs(s, component),
                wind_cs: wind_cs(s, component),
                dt: h,
                dt_old: h,
                part: 1.0,
                fixed,
                world: None,
                push: &[],
                accel: &[],
                base: None,
                params,
                list: list_of(rig, shared_lists, ci),
                every: every_of(rig, every),
            }
        };
        for _ in 0..s.warmup_steps {
            step_group(
                rig,
                group.into(),
                &input_of,
                pos,
                prev,
                rng,
                lambda,
                &mut Bridges {
                    pos: bridge_pos,
                    prev: bridge_prev,
                    feedback,
                },
            );
        }
    }
    for &ci in &group.chains {
        for p in rig.chains[ci].points.clone() {
            state.dev[p] = state.pos[p] - state.targets[p];
            state.dev_before[p] = state.dev[p];
        }
    }
}

/// A fixed-mode frame of a group: its chains share one clock (the compile checks their
/// rates agree), so every step places all their targets, then steps them together.
fn run_fixed_group(
    rig: &ChainRig,
    group: &ChainGroup,
    state: &mut ChainState,
    dt: f32,
    level: Option<&Level>,
) {
    let lead = group.chains[0];
    let s = &rig.chains[lead].settings;
    let h = 1.0 / s.target_framerate;
    let acc_old = state.accumulator[lead];
    let (steps, total, skipped) = fixed_steps(s, acc_old, dt);
    for k in 1..=steps {
        let w = step_end(k, h, acc_old, skipped, dt);
        scale_settings(rig, &group.chains, state, (1.0 - w) * dt);
        for &ci in &group.chains {
            place_step(rig, ci, state, w);
        }
        if !group.bridges.is_empty() {
            // The bridge points collide with every collider.
            let every = std::mem::take(&mut state.every);
            place_step_colliders(every_of(rig, &every), state, w);
            state.every = every;
        }
        let comp_b = state.path.at(w);
        let from = state.last_step_component[lead];
        for &ci in &group.chains {
            state.world_near[ci] = world_for(
                rig,
                ci,
                level,
                state.params.radius_scale(ci),
                &state.pos,
                &state.step_targets,
                &from,
                &comp_b,
            )
            .is_some();
        }
        for &ci in &group.chains {
            let base_b = state.base_prev[ci].lerp(&state.base_now[ci], w);
            state.space_in[ci] = space_step(rig, ci, state, from, comp_b, base_b);
            state
                .forces
                .prepare(rig, ci, h, w, &comp_b, &state.pos, &state.step_targets);
        }
        {
            let ChainState {
                pos,
                prev,
                rng,
                lambda,
                bridge_pos,
                bridge_prev,
                feedback,
                step_targets,
                step_normals,
                step_colliders,
                step_bounds,
                world_near,
                forces,
                space_in,
                params,
                shared_lists,
                every,
                ..
            } = &mut *state;
            let forces = &*forces;
            let params = params.view(rig);
            let input_of = |ci: usize| {
                let s = &rig.chains[ci].settings;
                let (move_cs, rotate_cs, base) = space_in[ci];
                StepInput {
                    targets: step_targets,
                    normals: step_normals,
                    colliders: step_colliders,
                    bounds: step_bounds,
                    move_cs,
                    rotate_cs,
                    gravity_cs: gravity_cs(s, &comp_b),
                    wind_cs: wind_cs(s, &comp_b),
                    dt: h,
                    dt_old: h,
                    part: 1.0,
                    fixed: true,
                    world: level.filter(|_| world_near[ci]).map(|level| WorldContact {
                        level,
                        from,
                        to: comp_b,
                    }),
                    push: if forces.reaches(ci) {
                        &forces.push
                    } else {
                        &[]
                    },
                    accel: &forces.accel,
                    base,
                    params,
                    list: list_of(rig, shared_lists, ci),
                    every: every_of(rig, every),
                }
            };
            step_group(
                rig,
                group.into(),
                &input_of,
                pos,
                prev,
                rng,
                lambda,
                &mut Bridges {
                    pos: bridge_pos,
                    prev: bridge_prev,
                    feedback,
                },
            );
        }
        for &ci in &group.chains {
            state.last_step_component[ci] = comp_b;
        }
    }
    for &ci in &group.chains {
        state.accumulator[ci] = (total - steps as f32 * h).max(0.0);
    }
}

/// Turns each simulated parent toward its simulated children (mean direction), on top of
/// its animated rotation, and writes the local rotation.
pub(crate) fn write_back(
    sk: &Skeleton,
    rig: &ChainRig,
    targets: &[Vec3],
    out: &[Vec3],
    locals: &mut [Transform],
    models: &mut [Transform],
    lanes: bool,
) {
    let mut turn = |r: usize| {
        let (joint, point, kids) = &rig.rotators[r];
        let j = *joint as usize;
        let p = *point as usize;
        let mut anim = Vec3::ZERO;
        let mut sim = Vec3::ZERO;
        for &c in &rig.rotator_children[kids.start as usize..kids.end as usize] {
            let c = c as usize;
            anim += normalize_or(targets[c] - targets[p], Vec3::ZERO);
            sim += normalize_or(out[c] - out[p], Vec3::ZERO);
        }
        if anim.length_squared() < 1e-12 || sim.length_squared() < 1e-12 {
            return;
        }
        let swing = rotation_arc(anim, sim);
        let new_rot = (swing * models[j].rotation).normalize();
        let parent_rot = sk
            .parent(j)
            .map(|q| models[q].rotation)
            .unwrap_or(Quat::IDENTITY);
        locals[j].rotation = (parent_rot.inverse() * new_rot).normalize();
        models[j].rotation = new_rot;
    };
    // With the lanes on, the rotators of lane groups were written back there, before.
    if lanes {
        rig.scalar_rotators.iter().for_each(|&r| turn(r as usize));
    } else {
        (0..rig.rotators.len()).for_each(turn);
    }
}
