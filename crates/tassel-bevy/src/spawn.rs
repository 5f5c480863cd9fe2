//! A skeleton made in code (or read by `tassel_gltf`) spawned as Bevy entities.

use crate::convert::to_bevy;
use bevy::ecs::prelude::*;
use bevy::prelude::{ChildOf, Name};
use tassel::Skeleton;

/// Spawns `skeleton` at rest below `parent`: one entity per joint, named as the joint (as
/// [`crate::TasselModel::new`] finds bones), with its rest `Transform`, each under its
/// parent joint's entity (a root joint under `parent`). Returns the joints' entities in
/// joint order. For characters built in code: put the [`crate::SecondaryMotion`] on
/// `parent`.
pub fn spawn_skeleton(world: &mut World, skeleton: &Skeleton, parent: Entity) -> Vec<Entity> {
    let mut entities: Vec<Entity> = Vec::with_capacity(skeleton.len());
    for j in 0..skeleton.len() {
        let up = skeleton.parent(j).map_or(parent, |p| entities[p]);
        let e = world
            .spawn((
                Name::new(skeleton.name(j).to_string()),
                to_bevy(&skeleton.rest()[j]),
                ChildOf(up),
            ))
            .id();
        entities.push(e);
    }
    entities
}
