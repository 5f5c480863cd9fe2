//! One frame of every bound character: read the animated bone `Transform`s, step, write
//! the simulated bones back (before Bevy propagates transforms).

use crate::character::TasselCharacter;
use crate::TasselError;
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::prelude::{ChildOf, Transform};
use bevy::time::Time;

/// Bevy's `Transform` as Tassel's (the same glam types).
pub(crate) fn to_tassel(t: &Transform) -> tassel::Transform {
    tassel::Transform::new(t.translation, t.rotation, t.scale)
}

/// The world transform of `entity` from this frame's local `Transform`s (not last frame's
/// `GlobalTransform`: propagation has not run yet), composed as Tassel composes.
pub(crate) fn world_of(
    entity: Option<Entity>,
    transforms: &Query<&mut Transform>,
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

pub(crate) fn step_characters(
    time: Res<Time>,
    mut characters: Query<(Entity, &mut TasselCharacter)>,
    mut transforms: Query<&mut Transform>,
    parents: Query<&ChildOf>,
    mut errors: MessageWriter<TasselError>,
) {
    let dt = time.delta_secs();
    for (entity, mut character) in &mut characters {
        let c = &mut *character;
        // The animated pose: every bone's Transform as the animation left it. A simulated
        // bone that still holds what the plugin wrote last frame was not animated since
        // (no clip drives it): it keeps its last animated pose. A bone without an entity
        // stays at rest.
        let mut w = 0;
        for (j, local) in c.locals.iter_mut().enumerate() {
            let mine = match c.written.get(w) {
                Some(&(k, _)) if k == j => {
                    w += 1;
                    c.wrote[w - 1]
                }
                _ => None,
            };
            if let Some(t) = c.bones[j].and_then(|e| transforms.get(e).ok()) {
                let t = to_tassel(t);
                if mine != Some(t) {
                    *local = t;
                }
            }
        }
        let component = world_of(c.space, &transforms, &parents);
        let dt = if c.first_frame {
            c.sim.reset();
            0.0
        } else {
            dt
        };
        match c.sim.frame(&c.locals, component, dt) {
            Ok(pose) => {
                c.first_frame = false;
                c.last_error = None;
                for (&(j, e), wrote) in c.written.iter().zip(&mut c.wrote) {
                    if let Ok(mut t) = transforms.get_mut(e) {
                        let l = pose.locals[j];
                        t.translation = l.translation;
                        t.rotation = l.rotation;
                        t.scale = l.scale;
                        *wrote = Some(l);
                    }
                }
            }
            Err(e) => {
                // The bones keep their animated pose; the next good frame carries on.
                let message = e.to_string();
                if c.last_error.as_deref() != Some(message.as_str()) {
                    warn!("tassel: entity {entity}: frame skipped: {message}");
                    errors.write(TasselError {
                        entity,
                        message: message.clone(),
                    });
                    c.last_error = Some(message);
                }
            }
        }
    }
}
