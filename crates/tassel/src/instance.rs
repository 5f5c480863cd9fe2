//! One character's secondary-motion frame, wiring skeleton, chain rig and state together.

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
use std::sync::Arc;

/// A character ready to simulate: its skeleton, compiled rig, state and last pose.
///
/// ```
/// use tassel::{builtin, CharacterSim, Transform};
/// let c = builtin::character();
/// let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
/// let rest = c.skeleton.rest().to_vec();
/// let pose = sim.frame(&rest, Transform::IDENTITY, 1.0 / 60.0).unwrap();
/// assert_eq!(pose.locals.len(), c.skeleton.len());
/// ```
#[derive(Debug, Clone)]
pub struct CharacterSim {
    skeleton: Skeleton,
    rig: ChainRig,
    state: ChainState,
    springs: SpringRig,
    spring_state: SpringState,
    cloths: ClothRig,
    cloth_state: ClothState,
    ropes: Ropes,
    vrm: VrmRig,
    vrm_state: VrmState,
    pose: Pose,
    animated_models: Vec<Transform>,
    level: Option<Arc<Level>>,
}

impl CharacterSim {
    /// Compiles `rig` for `skeleton`.
    pub fn new(skeleton: Skeleton, rig: &RigSettings) -> Result<Self> {
        Self::with_vrm(
            skeleton,
            rig,
            &VrmSpringBones::default(),
            VrmOptions::default(),
        )
    }

    /// Compiles `rig` and a model's VRM spring bones for `skeleton`. The VRM springs run
    /// first (on the animated pose), then chains, springs, cloths and ropes; a bone may
    /// belong to one solver only.
    pub fn with_vrm(
        skeleton: Skeleton,
        rig: &RigSettings,
        vrm: &VrmSpringBones,
        options: VrmOptions,
    ) -> Result<Self> {
        let vrm = VrmRig::new(&skeleton, vrm, options)?;
        let vrm_state = VrmState::new(&vrm);
        let chains = ChainRig::new(&skeleton, rig)?;
        let state = ChainState::new(&chains);
        let springs = SpringRig::new(&skeleton, &rig.springs)?;
        let spring_state = SpringState::new(&springs);
        let cloths = ClothRig::new(&skeleton, rig)?;
        let cloth_state = ClothState::new(&cloths);
        rig.validate_for(&skeleton)?;
        let ropes = Ropes::new(&skeleton, rig)?;
        // One solver per bone, checked in one pass over an owner table (a rig may list
        // thousands of bones). A chain owns the joints it moves and the joints it turns
        // (its roots included); several chains may share a root, several cloths a bone.
        let mut owner: Vec<Option<&'static str>> = vec![None; skeleton.len()];
        let mut claim = |j: usize, who: &'static str| -> Result<()> {
            match owner[j] {
                Some(other) if other != who => Err(Error::InvalidParameter(format!(
                    "bone '{}' is simulated by a {other} and by a {who}; a bone belongs \
                     to one solver",
                    skeleton.name(j)
                ))),
                _ => {
                    owner[j] = Some(who);
                    Ok(())
                }
            }
        };
        for j in vrm.simulated_joints() {
            claim(j, "VRM spring")?;
        }
        for p in 0..chains.point_count() {
            let info = chains.point(p);
            if let (Some(j), Some(_)) = (info.joint, info.parent) {
                claim(j, "chain")?;
            }
        }
        for (j, _, _) in chains.rotating_joints() {
            claim(j, "chain")?;
        }
        for i in 0..springs.len() {
            claim(springs.joint(i), "spring")?;
        }
        for j in cloths.simulated_joints() {
            claim(j, "cloth")?;
        }
        for j in ropes.simulated_joints() {
            claim(j, "rope")?;
        }
        let pose = Pose::rest(&skeleton);
        let animated_models = pose.models.clone();
        Ok(Self {
            skeleton,
            rig: chains,
            state,
            springs,
            spring_state,
            cloths,
            cloth_state,
            ropes,
            vrm,
            vrm_state,
            pose,
            animated_models,
            level: None,
        })
    }

    /// Runs one frame: `animated` local pose, the character's world transform, frame time.
    /// Returns the pose with simulated rotations (model space = character space).
    pub fn frame(
        &mut self,
        animated: &[Transform],
        component: Transform,
        dt: f32,
    ) -> Result<&Pose> {
        if animated.len() != self.skeleton.len() {
            return Err(Error::LengthMismatch {
                what: "animated pose",
                expected: self.skeleton.len(),
                got: animated.len(),
            });
        }
        // Checked here, once, before any solver state is touched: a bad frame is an error
        // and the next good frame carries on from where the last good one left off.
        if let Some(j) = animated.iter().position(|t| !t.within_limits()) {
            return Err(Error::NonFinite(format!(
                "animated pose of joint '{}' is not finite, not a unit rotation, or lies \
                 beyond {:e}",
                self.skeleton.name(j),
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
        self.pose.locals.copy_from_slice(animated);
        LocalToModelJob {
            skeleton: &self.skeleton,
            root: Transform::IDENTITY,
            locals: &self.pose.locals,
            models: &mut self.pose.models,
        }
        .run()?;
        self.animated_models.copy_from_slice(&self.pose.models);
        if !self.vrm.is_empty() {
            VrmJob {
                skeleton: &self.skeleton,
                rig: &self.vrm,
                state: &mut self.vrm_state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
            }
            .run()?;
        }
        ChainJob {
            skeleton: &self.skeleton,
            rig: &self.rig,
            state: &mut self.state,
            component,
            dt,
            locals: &mut self.pose.locals,
            models: &mut self.pose.models,
            level: self.level.as_deref(),
        }
        .run()?;
        if !self.springs.is_empty() {
            SpringJob {
                skeleton: &self.skeleton,
                rig: &self.springs,
                state: &mut self.spring_state,
                component,
                dt,
                locals: &mut self.pose.locals,
                models: &mut self.pose.models,
            }
            .run()?;
        }
        if !self.cloths.is_empty() {
            ClothJob {
                skeleton: &self.skeleton,
                rig: &self.cloths,
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
            &self.skeleton,
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
        &self.skeleton
    }

    /// The compiled chains.
    pub fn chains(&self) -> &ChainRig {
        &self.rig
    }

    /// The chain state (output positions, placed colliders...).
    pub fn state(&self) -> &ChainState {
        &self.state
    }

    /// The compiled springs.
    pub fn springs(&self) -> &SpringRig {
        &self.springs
    }

    /// The spring state.
    pub fn spring_state(&self) -> &SpringState {
        &self.spring_state
    }

    /// The compiled cloths.
    pub fn cloths(&self) -> &ClothRig {
        &self.cloths
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
        &self.vrm
    }

    /// The VRM spring-bone state.
    pub fn vrm_state(&self) -> &VrmState {
        &self.vrm_state
    }

    /// Every joint a solver writes (VRM springs, chain joints that turn or move, springs,
    /// cloth and rope bones), sorted, each once: the joints a bake must key.
    pub fn simulated_joints(&self) -> Vec<usize> {
        let mut out: Vec<usize> = self.vrm.simulated_joints().collect();
        out.extend(self.rig.rotating_joints().map(|(j, _, _)| j));
        out.extend((0..self.rig.point_count()).filter_map(|p| {
            let info = self.rig.point(p);
            info.parent.and(info.joint)
        }));
        out.extend((0..self.springs.len()).map(|i| self.springs.joint(i)));
        out.extend(self.cloths.simulated_joints());
        out.extend(self.ropes.simulated_joints());
        out.sort_unstable();
        out.dedup();
        out
    }

    /// The last output pose.
    pub fn pose(&self) -> &Pose {
        &self.pose
    }

    /// The last animated (input) model pose.
    pub fn animated_models(&self) -> &[Transform] {
        &self.animated_models
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
