//! Binding a [`SecondaryMotion`] to its bones: waiting for the assets and the spawned
//! scene, finding each joint's entity by name, compiling (or sharing) the character.

use crate::assets::{TasselModel, TasselRig};
use crate::character::{SecondaryMotion, TasselCharacter, TasselFailed};
use crate::TasselError;
use bevy::asset::{AssetEvent, AssetId, AssetServer, Assets, LoadState};
use bevy::ecs::prelude::*;
use bevy::log::{error, warn};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::{ChildOf, Children, Name};
use std::collections::VecDeque;
use std::sync::{Arc, Weak};
use tassel::crowd::CrowdKind;
use tassel::dynamics::vrm::VrmSpringBones;
use tassel::dynamics::{RigSettings, SimMode};
use tassel::{CharacterRig, CharacterSim};

/// What makes two characters the same kind: they share one compiled rig.
type RigKey = (
    AssetId<TasselModel>,
    Option<AssetId<TasselRig>>,
    &'static str,
    bool,
    // The VRM step rate's bits and the most steps per frame, when set.
    Option<u32>,
    Option<u32>,
);

/// Compiled rigs by kind, held weakly: the last character of a kind to go frees it.
#[derive(Resource, Default)]
pub(crate) struct RigCache {
    rigs: HashMap<RigKey, Weak<CharacterRig>>,
}

impl RigCache {
    /// How many kinds of character are alive (for tests and diagnostics).
    pub(crate) fn live(&self) -> usize {
        self.rigs.values().filter(|w| w.strong_count() > 0).count()
    }
}

/// Frames spent waiting for a scene's root bone, per character (a warning after a while).
#[derive(Default)]
pub(crate) struct Waiting(HashMap<Entity, u32>);

const WARN_AFTER_FRAMES: u32 = 600;

/// A character entity: what it asks for, and whether it runs or failed.
type CharacterQuery = (
    Entity,
    Ref<'static, SecondaryMotion>,
    Has<TasselCharacter>,
    Has<TasselFailed>,
);

#[allow(clippy::too_many_arguments)]
pub(crate) fn bind_characters(
    mut commands: Commands,
    characters: Query<CharacterQuery>,
    models: Res<Assets<TasselModel>>,
    rigs: Res<Assets<TasselRig>>,
    server: Res<AssetServer>,
    names: Query<&Name>,
    children: Query<&Children>,
    parents: Query<&ChildOf>,
    mut cache: ResMut<RigCache>,
    mut model_events: MessageReader<AssetEvent<TasselModel>>,
    mut rig_events: MessageReader<AssetEvent<TasselRig>>,
    mut errors: MessageWriter<TasselError>,
    mut waiting: Local<Waiting>,
    #[cfg(feature = "gltf")] scenes: Query<&bevy::world_serialization::WorldAssetRoot>,
) {
    // Hot reload: a changed model or rig restarts the characters that use it.
    let mut modified_models = HashSet::new();
    let mut modified_rigs = HashSet::new();
    for e in model_events.read() {
        if let AssetEvent::Modified { id } = e {
            modified_models.insert(*id);
        }
    }
    for e in rig_events.read() {
        if let AssetEvent::Modified { id } = e {
            modified_rigs.insert(*id);
        }
    }
    if !modified_models.is_empty() || !modified_rigs.is_empty() {
        cache.rigs.retain(|k, _| {
            !modified_models.contains(&k.0) && !k.1.is_some_and(|r| modified_rigs.contains(&r))
        });
    }
    waiting.0.retain(|e, _| characters.contains(*e));
    for (entity, motion, bound, failed) in &characters {
        let reload = modified_models.contains(&motion.model.id())
            || motion
                .rig
                .as_ref()
                .is_some_and(|r| modified_rigs.contains(&r.id()));
        let changed = motion.is_changed() && !motion.is_added();
        if (bound || failed) && !(changed || reload) {
            continue;
        }
        if bound || failed {
            commands
                .entity(entity)
                .remove::<(TasselCharacter, TasselFailed)>();
        }
        let mut fail = |message: String| {
            error!("tassel: entity {entity}: {message}");
            errors.write(TasselError {
                entity,
                message: message.clone(),
            });
            commands.entity(entity).insert(TasselFailed(message));
        };
        // The assets.
        let Some(model) = models.get(&motion.model) else {
            if let LoadState::Failed(e) = server.load_state(&motion.model) {
                fail(format!("the model did not load: {e}"));
            }
            continue;
        };
        let rig = match &motion.rig {
            None => None,
            Some(handle) => match rigs.get(handle) {
                Some(r) => Some(r),
                None => {
                    if let LoadState::Failed(e) = server.load_state(handle) {
                        fail(format!("the rig did not load: {e}"));
                    }
                    continue;
                }
            },
        };
        // The bones: the root's entity first (the scene may not be spawned yet).
        let skeleton = model.skeleton();
        let root_name = model.entity_name(0).unwrap_or_default();
        let Some(_) = find_below(entity, root_name, &names, &children) else {
            // A scene that failed to load will never bring the bones.
            #[cfg(feature = "gltf")]
            if let Ok(scene) = scenes.get(entity) {
                if let LoadState::Failed(e) = server.load_state(&scene.0) {
                    waiting.0.remove(&entity);
                    fail(format!("the scene did not load: {e}"));
                    continue;
                }
            }
            let n = waiting.0.entry(entity).or_default();
            *n += 1;
            if *n == WARN_AFTER_FRAMES {
                warn!(
                    "tassel: entity {entity}: no entity named '{root_name}' (the model's root \
                     bone) below it after {WARN_AFTER_FRAMES} frames; still waiting"
                );
            }
            continue;
        };
        waiting.0.remove(&entity);
        let bones = map_bones(entity, model, &names, &children);
        // The compiled kind, shared.
        let key: RigKey = (
            motion.model.id(),
            motion.rig.as_ref().map(|r| r.id()),
            motion.mode.name(),
            motion.vrm_springs,
            motion.vrm_step_rate.map(f32::to_bits),
            motion.max_steps_per_frame,
        );
        let compiled = match cache.rigs.get(&key).and_then(Weak::upgrade) {
            Some(c) => c,
            None => match compile(model, rig.map(|r| &r.0), &motion) {
                Ok(c) => {
                    let c = Arc::new(c);
                    cache.rigs.retain(|_, w| w.strong_count() > 0);
                    cache.rigs.insert(key, Arc::downgrade(&c));
                    c
                }
                Err(e) => {
                    fail(e);
                    continue;
                }
            },
        };
        // Every simulated bone and its ancestors need an entity: their animated pose
        // drives the motion.
        let mut needed = vec![false; skeleton.len()];
        for &j in compiled.simulated_joints() {
            let mut k = Some(j);
            while let Some(i) = k {
                if needed[i] {
                    break;
                }
                needed[i] = true;
                k = skeleton.parent(i);
            }
        }
        if let Some(j) = (0..skeleton.len()).find(|&j| needed[j] && bones[j].is_none()) {
            fail(format!(
                "bone '{}' has no entity named '{}' below this entity",
                skeleton.name(j),
                model.entity_name(j).unwrap_or_default()
            ));
            continue;
        }
        let written: Vec<(usize, Entity)> = compiled
            .simulated_joints()
            .iter()
            .filter_map(|&j| bones[j].map(|e| (j, e)))
            .collect();
        let space = bones[0].and_then(|root| parents.get(root).ok().map(ChildOf::parent));
        let locals = skeleton.rest().to_vec();
        // A kind that runs as a crowd steps there (the step system adds the character);
        // any other, or a character asked to stay apart, on its own sim.
        let sim = (!motion.crowd || CrowdKind::of(&compiled).is_none())
            .then(|| CharacterSim::from_rig(compiled.clone()));
        commands.entity(entity).insert(TasselCharacter {
            rig: compiled,
            sim,
            slot: None,
            bones,
            space,
            first_frame: true,
            last_error: None,
            locals,
            root: tassel::Transform::IDENTITY,
            result: None,
            wrote: vec![None; written.len()],
            written,
        });
    }
}

/// Compiles a model with an optional rig as `motion` asks (mode, VRM springs, stepping).
fn compile(
    model: &TasselModel,
    rig: Option<&RigSettings>,
    motion: &SecondaryMotion,
) -> Result<CharacterRig, String> {
    let (mode, vrm_springs) = (motion.mode, motion.vrm_springs);
    let mut settings = rig.cloned().unwrap_or_default();
    let empty = VrmSpringBones::default();
    let vrm = match model.vrm() {
        Some(v) if vrm_springs => v,
        _ => &empty,
    };
    let has_vrm = !vrm.springs.is_empty();
    // Spec and three-vrm are VRM modes; without VRM springs they step the chains as the
    // rig file says (fixed unless it asks for classic).
    let requested = match mode {
        SimMode::Spec | SimMode::ThreeVrm if !has_vrm => None,
        m => Some(m),
    };
    let (_, mut options) =
        SimMode::apply(requested, &mut settings, has_vrm).map_err(|e| e.to_string())?;
    if let Some(rate) = motion.vrm_step_rate {
        options.step_rate = rate;
    }
    if let Some(n) = motion.max_steps_per_frame {
        options.max_steps_per_frame = n;
    }
    CharacterRig::with_vrm((**model.skeleton()).clone(), &settings, vrm, options)
        .map_err(|e| format!("the character does not compile: {e}"))
}

/// The first entity named `name` at or below `root`, breadth first.
fn find_below(
    root: Entity,
    name: &str,
    names: &Query<&Name>,
    children: &Query<&Children>,
) -> Option<Entity> {
    let mut queue = VecDeque::from([root]);
    while let Some(e) = queue.pop_front() {
        if names.get(e).is_ok_and(|n| n.as_str() == name) {
            return Some(e);
        }
        if let Ok(c) = children.get(e) {
            queue.extend(c.iter());
        }
    }
    None
}

/// Each joint's entity: a root joint is the first entity with its name at or below
/// `root`; any other joint is a child of its parent joint's entity with its name (the
/// k-th such child for the k-th joint of that name under that parent, glTF child order).
fn map_bones(
    root: Entity,
    model: &TasselModel,
    names: &Query<&Name>,
    children: &Query<&Children>,
) -> Vec<Option<Entity>> {
    let skeleton = model.skeleton();
    let mut bones: Vec<Option<Entity>> = vec![None; skeleton.len()];
    // Joints come parents first (depth-first order).
    for j in 0..skeleton.len() {
        let name = model.entity_name(j).unwrap_or_default();
        bones[j] = match skeleton.parent(j) {
            None => find_below(root, name, names, children),
            Some(p) => bones[p].and_then(|pe| {
                let rank = skeleton
                    .children(p)
                    .take_while(|&c| c != j)
                    .filter(|&c| model.entity_name(c) == Some(name))
                    .count();
                children
                    .get(pe)
                    .ok()?
                    .iter()
                    .filter(|&c| names.get(c).is_ok_and(|n| n.as_str() == name))
                    .nth(rank)
            }),
        };
    }
    bones
}
