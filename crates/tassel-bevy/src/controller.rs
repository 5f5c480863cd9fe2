//! Tassel's character controller as components: every entity with a [`TasselCollider`]
//! is a collider of one [`TasselLevel`] (added, moved and removed with its entity), and
//! every entity with a [`CharacterController`] is a capsule moved through that level by
//! `desired`, each frame, in [`TasselSystems::Control`](crate::TasselSystems::Control).
//!
//! A collider's world pose is composed from this frame's `Transform`s up its parents
//! (scale ignored), so a platform moved in `Update` carries the characters standing on it
//! in the same frame. A controlled entity must be a root (no parent): the controller owns
//! its world translation, and turns its rotation with the platform under it.

use crate::TasselError;
use bevy::ecs::prelude::*;
use bevy::math::{Quat, Vec3};
use bevy::platform::collections::HashMap;
use bevy::time::Time;
use bevy::transform::components::Transform;
use tassel::controller::{
    CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape, Movement,
    DEFAULT_GROUPS,
};

/// A level collider: its shape in the entity's frame, placed by the entity's world
/// transform (scale ignored), in the collision groups `groups`.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct TasselCollider {
    /// The geometry, in the entity's frame.
    pub shape: LevelShape,
    /// Collision groups, one bit each (default [`DEFAULT_GROUPS`]).
    pub groups: u32,
}

impl TasselCollider {
    /// A collider of `shape` in the default groups.
    pub fn new(shape: LevelShape) -> Self {
        Self {
            shape,
            groups: DEFAULT_GROUPS,
        }
    }
}

/// The level made of every [`TasselCollider`], kept in step with their entities once per
/// frame in [`TasselSystems::Level`](crate::TasselSystems::Level).
#[derive(Resource)]
pub struct TasselLevel {
    level: Level,
    ids: HashMap<Entity, usize>,
    entities: HashMap<usize, Entity>,
}

impl Default for TasselLevel {
    fn default() -> Self {
        Self {
            level: Level::new(Vec::new()).expect("an empty level is valid"),
            ids: HashMap::default(),
            entities: HashMap::default(),
        }
    }
}

impl TasselLevel {
    /// The level, for queries (`ray`, `sweep_capsule`) or for `CharacterSim::set_level`
    /// users who clone what they need.
    pub fn level(&self) -> &Level {
        &self.level
    }

    /// The entity of level collider `id` (as in `Movement::platform` and hits).
    pub fn entity(&self, id: usize) -> Option<Entity> {
        self.entities.get(&id).copied()
    }

    /// The level collider id of `entity`.
    pub fn collider_id(&self, entity: Entity) -> Option<usize> {
        self.ids.get(&entity).copied()
    }

    fn remove(&mut self, entity: Entity) {
        if let Some(id) = self.ids.remove(&entity) {
            self.entities.remove(&id);
            self.level.remove(id);
        }
    }
}

/// A kinematic character: a capsule (axis along the entity's local Y) moved through the
/// [`TasselLevel`] by `desired` metres each frame. Set `desired` (with gravity: the
/// caller's, as in the core) before [`TasselSystems::Control`](crate::TasselSystems::Control);
/// it is cleared after the move, and `last` holds what the move did.
#[derive(Component, Debug, Clone, PartialEq)]
pub struct CharacterController {
    /// How it moves (slopes, steps, skin, groups).
    pub settings: ControllerSettings,
    /// Its capsule.
    pub capsule: CharacterCapsule,
    /// The translation wanted this frame, metres, world space.
    pub desired: Vec3,
    /// The last move: grounded, sliding, the platform (a level collider id: see
    /// [`TasselLevel::entity`]) and its turn, hits.
    pub last: Movement,
}

impl CharacterController {
    /// A controller for `capsule` with default settings.
    pub fn new(capsule: CharacterCapsule) -> Self {
        Self {
            settings: ControllerSettings::default(),
            capsule,
            desired: Vec3::ZERO,
            last: Movement::default(),
        }
    }
}

/// The world pose of `entity` from this frame's `Transform`s (scale dropped).
fn world_pose(
    entity: Entity,
    transforms: &Query<&Transform>,
    parents: &Query<&ChildOf>,
) -> (Vec3, Quat) {
    let mut pose: Option<(Vec3, Quat)> = None;
    let mut at = Some(entity);
    while let Some(e) = at {
        if let Ok(t) = transforms.get(e) {
            pose = Some(match pose {
                None => (t.translation, t.rotation),
                Some((p, r)) => (t.translation + t.rotation * (t.scale * p), t.rotation * r),
            });
        }
        at = parents.get(e).ok().map(ChildOf::parent);
    }
    pose.unwrap_or((Vec3::ZERO, Quat::IDENTITY))
}

/// Brings the level in step with the collider entities: removed ones leave, new ones
/// enter, moved ones move (their motion over the frame is what carries and pushes
/// characters), a changed shape or group re-enters.
pub(crate) fn sync_level(
    mut level: ResMut<TasselLevel>,
    colliders: Query<(Entity, Ref<TasselCollider>)>,
    transforms: Query<&Transform>,
    parents: Query<&ChildOf>,
    mut removed: RemovedComponents<TasselCollider>,
    mut errors: MessageWriter<TasselError>,
) {
    let level = &mut *level;
    level.level.start_frame();
    for entity in removed.read() {
        level.remove(entity);
    }
    for (entity, collider) in &colliders {
        let (position, rotation) = world_pose(entity, &transforms, &parents);
        if collider.is_changed() && !collider.is_added() {
            level.remove(entity);
        }
        let result = match level.ids.get(&entity) {
            Some(&id) => {
                let now = level.level.collider(id).map(|c| (c.position, c.rotation));
                if now == Some((position, rotation)) {
                    Ok(())
                } else {
                    level.level.set_pose(id, position, rotation)
                }
            }
            None => {
                let mut c =
                    LevelCollider::new(format!("{entity}"), collider.shape.clone(), position)
                        .rotated(rotation);
                c.groups = collider.groups;
                level.level.add(c).map(|id| {
                    level.ids.insert(entity, id);
                    level.entities.insert(id, entity);
                })
            }
        };
        if let Err(e) = result {
            errors.write(TasselError {
                entity,
                message: format!("collider: {e}"),
            });
        }
    }
}

/// Moves every [`CharacterController`] by its `desired` translation.
pub(crate) fn move_characters(
    time: Res<Time>,
    level: Res<TasselLevel>,
    mut characters: Query<(Entity, &mut CharacterController, &mut Transform)>,
    parents: Query<&ChildOf>,
    mut errors: MessageWriter<TasselError>,
) {
    let dt = time.delta_secs();
    for (entity, mut c, mut t) in &mut characters {
        if parents.get(entity).is_ok() {
            errors.write(TasselError {
                entity,
                message: "a CharacterController entity must have no parent".into(),
            });
            continue;
        }
        let pose = tassel::Transform {
            translation: t.translation,
            rotation: t.rotation,
            scale: Vec3::ONE,
        };
        let c = &mut *c;
        // Into the component's last movement: its buffers are reused, no allocation.
        match c.settings.move_shape_into(
            &level.level,
            &c.capsule,
            &pose,
            c.desired,
            dt,
            &mut c.last,
        ) {
            Ok(()) => {
                let m = &c.last;
                t.translation += m.translation;
                if m.platform_rotation != Quat::IDENTITY {
                    t.rotation = (m.platform_rotation * t.rotation).normalize();
                }
                c.desired = Vec3::ZERO;
            }
            Err(e) => {
                errors.write(TasselError {
                    entity,
                    message: format!("controller: {e}"),
                });
            }
        }
    }
}
