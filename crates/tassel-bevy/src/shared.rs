//! Colliders shared between characters (KawaiiPhysics' shared collision): a
//! [`SharedCollisionTarget`] character's chains with `use_shared_collision` collide with the
//! colliders of its [`SharedCollisionSource`] characters (every collider, or a named
//! `[[collider_group]]`), placed where this frame's animated bones put them.

use crate::character::TasselCharacter;
use crate::convert::world_of;
use crate::TasselError;
use bevy::ecs::prelude::*;
use bevy::prelude::{ChildOf, Transform};
use tassel::collide::PlacedCollider;

/// Shares this character's colliders with [`SharedCollisionTarget`] characters: every
/// collider of its rig, or those of its `[[collider_group]]` named `group`, each where this
/// frame's animated bone puts it (a crowd member too; a collider whose bone has no entity
/// is not shared).
#[derive(Component, Debug, Default, Clone, PartialEq, Eq)]
pub struct SharedCollisionSource {
    /// The rig's collider group to share (`None`: every collider).
    pub group: Option<String>,
}

impl SharedCollisionSource {
    /// Shares every collider of the character's rig.
    pub fn all() -> Self {
        Self::default()
    }

    /// Shares the rig's `[[collider_group]]` named `group`.
    pub fn group(group: impl Into<String>) -> Self {
        Self {
            group: Some(group.into()),
        }
    }
}

/// Gives this character's chains with `use_shared_collision = true` the colliders of the
/// [`SharedCollisionSource`] entities `sources` before each step, placed by the sources'
/// animated bones of this frame (no frame of lag). Such a character steps on its own
/// simulation (its rig never steps in a crowd). A source without a [`TasselCharacter`]
/// yet shares nothing; an unknown group is a [`TasselError`] (once).
#[derive(Component, Debug, Default, Clone)]
pub struct SharedCollisionTarget {
    /// The source entities.
    pub sources: Vec<Entity>,
    scratch: Vec<PlacedCollider>,
    reported: bool,
}

impl SharedCollisionTarget {
    /// A target of `sources`.
    pub fn new(sources: impl IntoIterator<Item = Entity>) -> Self {
        Self {
            sources: sources.into_iter().collect(),
            ..Self::default()
        }
    }

    /// The colliders handed over before the last step (world space).
    pub fn colliders(&self) -> &[PlacedCollider] {
        &self.scratch
    }
}

/// Source `c`'s shared colliders into `out`: each collider of its group on its bone's
/// world transform composed from this frame's `Transform`s.
fn place_source(
    c: &TasselCharacter,
    source: &SharedCollisionSource,
    transforms: &Query<&Transform>,
    parents: &Query<&ChildOf>,
    out: &mut Vec<PlacedCollider>,
) -> Result<(), String> {
    let chains = c.rig().chains();
    let list = chains
        .shared_set(source.group.as_deref())
        .map_err(|e| format!("SharedCollisionSource: {e}"))?;
    for &k in list {
        let bone = chains.collider_bone(k);
        // (A collider whose bone has no entity is not shared.)
        if let Some(e) = c.bones.get(bone).copied().flatten() {
            let world = world_of(Some(e), transforms, parents);
            out.push(chains.collider_at(k, &world));
        }
    }
    Ok(())
}

/// Before the step: each target's sources' colliders into its simulation.
pub(crate) fn hand_over_shared_colliders(
    mut targets: Query<(Entity, &mut SharedCollisionTarget)>,
    mut characters: Query<&mut TasselCharacter>,
    sources: Query<&SharedCollisionSource>,
    transforms: Query<&Transform>,
    parents: Query<&ChildOf>,
    mut errors: MessageWriter<TasselError>,
) {
    for (entity, mut t) in &mut targets {
        let t = &mut *t;
        t.scratch.clear();
        for &s in &t.sources {
            let (Ok(source), Ok(c)) = (sources.get(s), characters.get(s)) else {
                continue;
            };
            if let Err(message) = place_source(c, source, &transforms, &parents, &mut t.scratch) {
                if !t.reported {
                    t.reported = true;
                    bevy::log::warn!("{message}");
                    errors.write(TasselError { entity: s, message });
                }
            }
        }
        if let Ok(mut c) = characters.get_mut(entity) {
            if let Some(sim) = c.sim_mut() {
                if let Err(e) = sim.set_shared_colliders(&t.scratch) {
                    errors.write(TasselError {
                        entity,
                        message: e.to_string(),
                    });
                }
            }
        }
    }
}
