//! The components a user touches: [`SecondaryMotion`] (what to simulate) and
//! [`TasselCharacter`] (the running simulation, added by the plugin).

use crate::assets::{TasselModel, TasselRig};
use bevy::asset::Handle;
use bevy::ecs::component::Component;
use bevy::ecs::entity::Entity;
use std::sync::Arc;
use tassel::dynamics::SimMode;
use tassel::{CharacterRig, CharacterSim, Skeleton};

/// Secondary motion for the hierarchy under this entity: put it on the entity that holds
/// a glTF/VRM scene (`WorldAssetRoot`, formerly `SceneRoot`) or on the root of any
/// hierarchy of named entities. Once the model (and rig) have loaded and the bones are
/// spawned, the plugin finds each bone by name below this entity, compiles the character
/// (shared with every character of the same model, rig and mode) and adds a
/// [`TasselCharacter`]; from then on it reads the animated bone `Transform`s each frame,
/// steps, and writes the simulated bones back before transform propagation.
///
/// Characters of one kind (the same model, rig and mode) whose only solver is VRM spring
/// bones, or bone chains, are stepped together in a crowd ([`tassel::crowd`]: SIMD lanes,
/// every core), bit for bit as one [`CharacterSim`] each; other kinds step one
/// `CharacterSim` per character, characters in parallel. `without_crowd` keeps a
/// character on its own `CharacterSim` (to read its solver states: [`TasselCharacter::sim`]).
///
/// Changing any field starts the character again (new rig, new mode).
#[derive(Component, Debug, Clone)]
pub struct SecondaryMotion {
    /// The model: its skeleton and, in a VRM, its spring bones.
    pub model: Handle<TasselModel>,
    /// An optional rig file (`.rig.toml`): chains, springs, cloths, ropes.
    pub rig: Option<Handle<TasselRig>>,
    /// How to step. [`SimMode::Fixed`] (the default) looks the same at every frame rate;
    /// [`SimMode::Spec`] steps VRM springs once per frame as the VRM specification does.
    pub mode: SimMode,
    /// Run the file's VRM spring bones (default `true`).
    pub vrm_springs: bool,
    /// Step with the other characters of its kind in a crowd where the kind allows
    /// (default `true`); `false` keeps its own [`CharacterSim`].
    pub crowd: bool,
    /// `fixed` mode: the VRM springs' steps per second (10..=1000; `None`: 60, the rate
    /// their parameters are tuned at). A rig file's chains, cloths and ropes keep the
    /// rates it gives them.
    pub vrm_step_rate: Option<f32>,
    /// `fixed` mode: the VRM springs' most steps in one frame (`None`: the default, 8);
    /// after a longer hitch the time beyond is dropped.
    pub max_steps_per_frame: Option<u32>,
}

impl SecondaryMotion {
    /// The model's own VRM spring bones, fixed-rate stepping.
    pub fn new(model: Handle<TasselModel>) -> Self {
        Self {
            model,
            rig: None,
            mode: SimMode::Fixed,
            vrm_springs: true,
            crowd: true,
            vrm_step_rate: None,
            max_steps_per_frame: None,
        }
    }

    /// `fixed` mode: the VRM springs step `rate` times a second (10..=1000; a value
    /// outside gives `TasselFailed` naming it).
    pub fn with_vrm_step_rate(mut self, rate: f32) -> Self {
        self.vrm_step_rate = Some(rate);
        self
    }

    /// `fixed` mode: the VRM springs take at most `n` steps in one frame.
    pub fn with_max_steps_per_frame(mut self, n: u32) -> Self {
        self.max_steps_per_frame = Some(n);
        self
    }

    /// Adds a rig file's chains, springs, cloths and ropes.
    pub fn with_rig(mut self, rig: Handle<TasselRig>) -> Self {
        self.rig = Some(rig);
        self
    }

    /// Sets the stepping mode.
    pub fn with_mode(mut self, mode: SimMode) -> Self {
        self.mode = mode;
        self
    }

    /// Leaves the file's VRM spring bones out (e.g. to run only a rig's chains).
    pub fn without_vrm_springs(mut self) -> Self {
        self.vrm_springs = false;
        self
    }

    /// Keeps this character on its own [`CharacterSim`] (never in a crowd), so that
    /// [`TasselCharacter::sim`] gives its solver states (the gizmos draw from them).
    pub fn without_crowd(mut self) -> Self {
        self.crowd = false;
        self
    }
}

/// The running simulation of a [`SecondaryMotion`] entity, added by the plugin once the
/// bones are found. The simulated bones' `Transform`s are the results (and, after
/// propagation, their `GlobalTransform`s); a character on its own [`CharacterSim`] also
/// gives its solver states through [`sim`](Self::sim). [`reset`](Self::reset) and
/// [`teleport`](Self::teleport) restart the motion from the animated pose.
#[derive(Component, Debug)]
pub struct TasselCharacter {
    /// The compiled kind (shared by every character of the same model, rig and mode).
    pub(crate) rig: Arc<CharacterRig>,
    /// The character's own simulation (`None`: stepped in its kind's crowd).
    pub(crate) sim: Option<CharacterSim>,
    /// Its index in its kind's crowd, once it joined (crowd path only).
    pub(crate) slot: Option<usize>,
    /// Joint → the entity that stands for it (`None`: not found, rest pose used).
    pub(crate) bones: Vec<Option<Entity>>,
    /// The simulated joints that have an entity: written back each frame.
    pub(crate) written: Vec<(usize, Entity)>,
    /// The entity whose world transform is the skeleton's model space (the parent of the
    /// root bone's entity).
    pub(crate) space: Option<Entity>,
    /// The next frame is the first: dt = 0 places every solver on the pose.
    pub(crate) first_frame: bool,
    /// The last frame's error, reported once until it changes.
    pub(crate) last_error: Option<String>,
    /// The animated local pose as last seen (what its own sim reads; a crowd member's is
    /// in its kind's buffer).
    pub(crate) locals: Vec<tassel::Transform>,
    /// This frame's world transform of the skeleton's model space (its own sim's input).
    pub(crate) root: tassel::Transform,
    /// This frame's error, between the step and the write-back.
    pub(crate) result: Option<String>,
    /// What the plugin wrote into each of `written` last frame: a bone still holding it
    /// was not animated since, and keeps its last animated pose as input (no feedback of
    /// the simulated pose into the next frame's input).
    pub(crate) wrote: Vec<Option<tassel::Transform>>,
}

impl TasselCharacter {
    /// The character's own simulation (its pose, solver states and world-space results as
    /// of the last frame); `None` for a character stepped in a crowd (see
    /// [`SecondaryMotion::without_crowd`]).
    pub fn sim(&self) -> Option<&CharacterSim> {
        self.sim.as_ref()
    }

    /// The character's own simulation, to steer at run time: external forces
    /// ([`CharacterSim::set_external_force`], [`CharacterSim::enable_external_force`], a
    /// force written in Rust with [`CharacterSim::set_custom_force`]), chain alphas, and
    /// animation events ([`CharacterSim::apply_events`] with a state machine's
    /// `BlendPlan::events`). `None` in a crowd: spawn with
    /// [`SecondaryMotion::without_crowd`] to steer one character of a crowdable kind (a
    /// rig file with external forces never steps in a crowd).
    pub fn sim_mut(&mut self) -> Option<&mut CharacterSim> {
        self.sim.as_mut()
    }

    /// The compiled kind of character: skeleton, solvers, simulated joints.
    pub fn rig(&self) -> &Arc<CharacterRig> {
        &self.rig
    }

    /// The model's skeleton (joint names and parents).
    pub fn skeleton(&self) -> &Skeleton {
        self.rig.skeleton()
    }

    /// The joints the solvers write, ascending.
    pub fn simulated_joints(&self) -> &[usize] {
        self.rig.simulated_joints()
    }

    /// The simulated bones' entities with their joints: the `Transform`s the plugin writes
    /// each frame.
    pub fn simulated_bones(&self) -> &[(usize, Entity)] {
        &self.written
    }

    /// Whether the character is stepped in its kind's crowd (not on its own
    /// [`CharacterSim`]).
    pub fn in_crowd(&self) -> bool {
        self.sim.is_none()
    }

    /// The entity that stands for the bone called `name`, if it was found.
    pub fn bone_entity(&self, name: &str) -> Option<Entity> {
        self.bones
            .get(self.skeleton().find(name)?)
            .copied()
            .flatten()
    }

    /// The entity whose world transform is the skeleton's model space (the parent of the
    /// root bone's entity; `None`: the root bone's entity has no parent, the world).
    pub fn space(&self) -> Option<Entity> {
        self.space
    }

    /// Starts every solver again from the animated pose on the next frame.
    pub fn reset(&mut self) {
        self.first_frame = true;
    }

    /// The character was moved on purpose (respawn, cut): start again from the pose at
    /// the new place instead of whipping the hair across the level.
    pub fn teleport(&mut self) {
        self.reset();
    }

    /// The last frame's error, if the last frame failed (e.g. a NaN in a bone's
    /// `Transform`); the bones keep their animated pose while it lasts.
    pub fn error(&self) -> Option<&str> {
        self.last_error.as_deref()
    }
}

/// Added instead of [`TasselCharacter`] when a character cannot run (a bone not found, a
/// rig that does not fit the skeleton, an asset that failed to load); the message says
/// why. Changing the [`SecondaryMotion`] tries again.
#[derive(Component, Debug, Clone, PartialEq, Eq)]
pub struct TasselFailed(pub String);
