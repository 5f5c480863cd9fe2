//! Transforms between Bevy and Tassel (the same glam types), and an entity's world
//! transform composed as Tassel composes: shared by the step and the crowds.

use bevy::ecs::prelude::*;
use bevy::prelude::{ChildOf, Transform};

/// Bevy's `Transform` as Tassel's (the same glam types).
pub(crate) fn to_tassel(t: &Transform) -> tassel::Transform {
    tassel::Transform::new(t.translation, t.rotation, t.scale)
}

/// Tassel's `Transform` as Bevy's.
pub(crate) fn to_bevy(t: &tassel::Transform) -> Transform {
    Transform {
        translation: t.translation,
        rotation: t.rotation,
        scale: t.scale,
    }
}

/// The world transform of `entity` from this frame's local `Transform`s (not last frame's
/// `GlobalTransform`: propagation has not run yet), composed as Tassel composes.
pub(crate) fn world_of(
    entity: Option<Entity>,
    transforms: &Query<&Transform>,
    parents: &Query<&ChildOf>,
) -> tassel::Transform {
    // Composed only where there is a parent: a lone entity's transform is used as it is
    // (composing with identity would renormalise its rotation).
    let mut world: Option<tassel::Transform> = None;
    let mut at = entity;
    while let Some(e) = at {
        if let Ok(t) = transforms.get(e) {
            let local = to_tassel(t);
            world = Some(match world {
                None => local,
                Some(w) => local * w,
            });
        }
        at = parents.get(e).ok().map(ChildOf::parent);
    }
    world.unwrap_or(tassel::Transform::IDENTITY)
}
