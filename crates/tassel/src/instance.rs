//! One character's secondary-motion frame: a shared compiled rig and this character's
//! states.

use crate::animated::{AnimatedModels, AnimatedPose};
use crate::character_rig::CharacterRig;
use crate::controller::Level;
use crate::dynamics::chain::{ChainJob, ChainRig, ChainState};
use crate::dynamics::cloth::{ClothJob, ClothRig, ClothState};
use crate::dynamics::rope::Ropes;
use crate::dynamics::spring::{SpringJob, SpringRig, SpringState};
use crate::dynamics::vrm::{VrmJob, VrmOptions, VrmRig, VrmSpringBones, VrmState};
use crate::dynamics::RigSettings;
use crate::error::{Error, Result};
use crate::math::Transform;
use crate::pose::{LocalToModelJob, Pose};
use crate::skeleton::Skeleton;
use glam::Vec3;
use std::sync::Arc;

mod control;
mod shared;
pub use control::EVENT_PREFIX;

/// A character ready to simulate: a shared compiled [`CharacterRig`], this character's
/// solver states and its last pose.
///
/// ```
/// use tassel::{builtin, CharacterSim, Transform};
/// let c = builtin::character();
/// let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
/// let rest = c.skeleton.rest().to_vec();
/// // The first frame takes dt = 0: it places every solver on the animated pose.
/// let pose = sim.frame(&rest, Transform::IDENTITY, 0.0).unwrap();
/// assert_eq!(pose.locals.len(), c.skeleton.len());
/// let pose = sim.frame(&rest, Transform::IDENTITY, 1.0 / 60.0).unwrap();
/// assert!(pose.models.iter().all(|m| m.is_finite()));
/// ```
///
/// **The first frame.** A character starts from its animated pose: the first
/// [`frame`](Self::frame) after [`new`](Self::new), [`from_rig`](Self::from_rig) or
/// [`reset`](Self::reset) places every solver on the pose and moves nothing, whatever its
/// `dt`. By convention callers pass `dt = 0` there (the CLI, the bake and the Bevy plugin
/// do), and the frame time since the previous frame afterwards.
#[derive(Debug, Clone)]
pub struct CharacterSim {
    rig: Arc<CharacterRig>,
    state: ChainState,
    spring_state: SpringState,
    cloth_state: ClothState,
    ropes: Ropes,
    vrm_state: VrmState,
    pose: Pose,
    animated: AnimatedPose,
    component: Transform,
    level: Option<Arc<Level>>,
}

impl CharacterSim {
    /// Compiles `rig` for `skeleton` (see [`CharacterRig::new`]); to share one compiled rig
    /// between characters, use [`from_rig`](Self::from_rig).
    pub fn new(skeleton: Skeleton, rig: &RigSettings) -> Result<Self> {
        Ok(Self::from_rig(Arc::new(CharacterRig::new(skeleton, rig)?)))
    }

    /// Compiles `rig` and a model's VRM spring bones for `skeleton` (see
    /// [`CharacterRig::with_vrm`]).
    pub fn with_vrm(
        skeleton: Skeleton,
        rig: &RigSettings,
        vrm: &VrmSpringBones,
        options: VrmOptions,
    ) -> Result<Self> {
        Ok(Self::from_rig(Arc::new(CharacterRig::with_vrm(
            skeleton, rig, vrm, options,
        )?)))
    }

    /// A new character of a compiled kind: fresh solver states, the rest pose. Cheap: the
    /// rig is shared, only the states are allocated.
    pub fn from_rig(rig: Arc<CharacterRig>) -> Self {
        let pose = Pose::rest(&rig.skeleton);
        let animated = AnimatedPose::new(&pose.models);
        Self {
            state: ChainState::new(&rig.chains),
            spring_state: SpringState::new(&rig.springs),
            cloth_state: ClothState::new(&rig.cloths),
            ropes: rig.ropes.clone(),
            vrm_state: VrmState::new(&rig.vrm),
            pose,
            animated,
            component: Transform::IDENTITY,
            level: None,
            rig,
        }
    }

    /// The shared compiled rig.
    pub fn rig(&self) -> &Arc<CharacterRig> {
        &self.rig
    }

    /// Runs one frame: `animated` local pose, the character's world transform, frame time.
    /// Returns the pose with simulated rotations (model space = character space).
    pub fn frame(
        &mut self,
        animated: &[Transform],
        component: Transform,
        dt: f32,
    ) -> Result<&Pose> {
        if animated.len() != self.rig.skeleton.len() {
            return Err(Error::LengthMismatch {
                what: "animated pose",
                expected: self.rig.skeleton.len(),
                got: animated.len(),
            });
        }
        // Checked here, once, before any solver state is touched: a bad frame is an error
        // and the next good frame carries on from where the last good one left off.
        // One pass without a branch per joint; the joint named only when one fails.
        let all_within = animated.iter().fold(true, |ok, t| ok & t.within_limits());
        let first_bad = || animated.iter().position(|t| !t.within_limits());
        if let Some(j) = (!all_within).then(first_bad).flatten() {
            return Err(Error::NonFinite(format!(
                "animated pose of joint '{}' is not finite, not a unit rotation, or lies \
                 beyond {:e}",
                self.rig.skeleton.name(j),
                crate::limits::MAX_COORDINATE
            )));
        }
        if !component.within_limits() {
            return Err(Error::NonFinite(format!(
                "character transform is not finite or lies beyond {:e}",
                crate::limits::MAX_COORDINATE
            )));
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidTimeStep(dt));
        }
        self.component = component;
        self.pose.locals.copy_from_slice(animated);
        let sk = &self.rig.skeleton;
        if let Some(lanes) = self.rig.vrm.lanes_for(self.vrm_state.simd()) {
            // The VRM job composes every joint a spring moves itself before reading it:
            // only the others are composed here (the job's output is the whole pose), and
            // the animated models wait until asked for.
            lanes.compose_input(sk, &self.pose.locals, &mut self.pose.models);
            self.animated.set_locals(animated);
        } else {
            LocalToModelJob {
                skeleton: sk,
                root: Transform::IDENTITY,
                locals: &self.pose.locals,
                models: &mut self.pose.models,
            }
            .run()?;
            self.animated.set_models(&self.pose.models);
        }
        if !self.rig.vrm.is_empty() {
            VrmJob {
                skeleton: &self.rig.skeleton,
                rig: &self.rig.vrm,
                state: &mut self.vrm_state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
            }
            .run_validated();
        }
        // Every solver leaves `models` the model pose of `locals`: one without work is
        // skipped (a chain job without chains would only compose the pose again).
        if !self.rig.chains.chains.is_empty() {
            ChainJob {
                skeleton: &self.rig.skeleton,
                rig: &self.rig.chains,
                state: &mut self.state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
                level: self.level.as_deref(),
            }
            .run()?;
        }
        if !self.rig.springs.is_empty() {
            SpringJob {
                skeleton: &self.rig.skeleton,
                rig: &self.rig.springs,
                state: &mut self.spring_state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
            }
            .run()?;
        }
        if !self.rig.cloths.is_empty() {
            ClothJob {
                skeleton: &self.rig.skeleton,
                rig: &self.rig.cloths,
                state: &mut self.cloth_state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
                level: self.level.as_deref(),
            }
            .run()?;
        }
        self.ropes.frame(
            &self.rig.skeleton,
            &component,
            dt,
            &mut self.pose.locals,
            &mut self.pose.models,
            self.level.as_deref(),
        )?;
        Ok(&self.pose)
    }

    /// Sets the world that chains with `world_collision` keep out of (the controller's
    /// [`Level`], shared: one world serves the controller and every character), or none.
    pub fn set_level(&mut self, level: Option<Arc<Level>>) {
        self.level = level;
    }

    /// The world the chains collide with, if any.
    pub fn level(&self) -> Option<&Level> {
        self.level.as_deref()
    }

    /// The skeleton.
    pub fn skeleton(&self) -> &Skeleton {
        &self.rig.skeleton
    }

    /// The compiled chains.
    pub fn chains(&self) -> &ChainRig {
        &self.rig.chains
    }

    /// The chain state (output positions, placed colliders...).
    pub fn chain_state(&self) -> &ChainState {
        &self.state
    }

    /// The chain state (the old name of [`chain_state`](Self::chain_state)).
    #[deprecated(note = "use chain_state(), named like spring_state(), cloth_state(), vrm_state()")]
    pub fn state(&self) -> &ChainState {
        &self.state
    }

    /// The compiled springs.
    pub fn springs(&self) -> &SpringRig {
        &self.rig.springs
    }

    /// The spring state.
    pub fn spring_state(&self) -> &SpringState {
        &self.spring_state
    }

    /// The compiled cloths.
    pub fn cloths(&self) -> &ClothRig {
        &self.rig.cloths
    }

    /// The cloth state (output positions, placed colliders...).
    pub fn cloth_state(&self) -> &ClothState {
        &self.cloth_state
    }

    /// The ropes and their particle worlds.
    pub fn ropes(&self) -> &Ropes {
        &self.ropes
    }

    /// The compiled VRM spring bones.
    pub fn vrm(&self) -> &VrmRig {
        &self.rig.vrm
    }

    /// The VRM spring-bone state.
    pub fn vrm_state(&self) -> &VrmState {
        &self.vrm_state
    }

    /// Which code runs the solvers that have a SIMD lane path (the VRM springs' update,
    /// the twin bone chains, [`ChainRig::lane_groups`], and the cloths' contact tests and
    /// constraint order): lanes by default, [`crate::lanes::SimdUse::Scalar`] for the
    /// readable reference. Every choice gives the same bits.
    pub fn set_simd(&mut self, simd: crate::lanes::SimdUse) {
        self.vrm_state.set_simd(simd);
        self.state.set_simd(simd);
        self.cloth_state.set_simd(simd);
    }

    /// Every joint a solver writes, ascending, each once (see
    /// [`CharacterRig::simulated_joints`]; no allocation).
    pub fn simulated_joints(&self) -> &[usize] {
        self.rig.simulated_joints()
    }

    /// The joint called `name`, if the skeleton has one.
    pub fn bone(&self, name: &str) -> Option<usize> {
        self.rig.skeleton.find(name)
    }

    /// The character's transform as of the last frame (identity before the first).
    pub fn component(&self) -> Transform {
        self.component
    }

    /// Joint `joint`'s last output transform in world space (the character's transform
    /// times its model transform); `None` past the last joint.
    pub fn bone_world(&self, joint: usize) -> Option<Transform> {
        Some(self.component * *self.pose.models.get(joint)?)
    }

    /// The last output world transform of the bone called `name`.
    pub fn bone_world_by_name(&self, name: &str) -> Option<Transform> {
        self.bone_world(self.bone(name)?)
    }

    /// The simulated tip of chain `name` (its last point, a bone or the virtual tip) in
    /// world space, as of the last frame.
    pub fn chain_tip_world(&self, name: &str) -> Option<Vec3> {
        let chain = self.rig.chain_index(name)?;
        let last = self.rig.chains.chain_points(chain).end.checked_sub(1)?;
        let p = *self.state.output_positions().get(last)?;
        Some(self.component.transform_point(p))
    }

    /// The current tail of the VRM spring link on joint `joint` in world space (where the
    /// spring's bone points), as of the last frame; `None` when no VRM spring moves it.
    pub fn vrm_tail_world(&self, joint: usize) -> Option<Vec3> {
        let link = self
            .rig
            .vrm
            .links
            .binary_search_by_key(&joint, |l| l.joint)
            .ok()?;
        self.vrm_state
            .tail_world(&self.rig.vrm, link, &self.component, &self.pose.models)
    }

    /// The swing limit (`VRMC_springBone_limit`) of the VRM spring link on joint `joint`
    /// as of the last frame, for drawing: `n` points of its boundary in world space at the
    /// bone's length from the joint (the cone's rim, the hinge's arc, the spherical box's
    /// outline), under the parent's current rotation. `None` when no limited spring link
    /// moves the joint.
    pub fn vrm_limit_outline(&self, joint: usize, n: usize) -> Option<Vec<Vec3>> {
        let vrm = &self.rig.vrm;
        let i = vrm.links.binary_search_by_key(&joint, |l| l.joint).ok()?;
        let link = &vrm.links[i];
        let limit = link.limit.as_ref()?;
        let parent = match link.parent {
            Some(p) => self.component * *self.pose.models.get(p)?,
            None => self.component,
        };
        let position = self.bone_world(joint)?.translation;
        let length = *self.vrm_state.lengths().get(i)?;
        Some(limit.outline_world(parent.rotation, position, length, n))
    }

    /// The last output pose.
    pub fn pose(&self) -> &Pose {
        &self.pose
    }

    /// The last animated (input) model pose: a slice of model transforms
    /// (`animated_models()[joint]`, `.iter()`). Composed on first use after a frame whose
    /// solvers did not need it whole (VRM springs in lanes compose their joints
    /// themselves); several may be held at once.
    pub fn animated_models(&self) -> AnimatedModels<'_> {
        self.animated.models(&self.rig.skeleton)
    }

    /// Starts the chains again from the animated pose on the next frame.
    pub fn reset(&mut self) {
        self.state.reset();
        self.spring_state.reset();
        self.cloth_state.reset();
        self.ropes.reset();
        self.vrm_state.reset();
    }
}
