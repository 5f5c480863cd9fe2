//! The animated (input) model pose a [`crate::CharacterSim`] keeps for its callers, composed
//! only when asked for on frames whose solvers did not need it whole.

use crate::math::Transform;
use crate::skeleton::Skeleton;
use std::ops::Deref;
use std::sync::{PoisonError, RwLock, RwLockReadGuard};

/// The last frame's animated model pose: complete, or the animated locals to compose it
/// from on first use. Behind a lock so that [`AnimatedPose::models`] can finish it through
/// a shared reference (the character stays `Send + Sync`); the frame itself writes through
/// `&mut` and never locks. A read lock: any number of [`AnimatedModels`] may be held at
/// once (the pose is complete before the first is handed out, so no writer waits).
#[derive(Debug, Default)]
pub(crate) struct AnimatedPose(RwLock<Inner>);

#[derive(Debug, Default, Clone)]
struct Inner {
    locals: Vec<Transform>,
    models: Vec<Transform>,
    complete: bool,
}

impl AnimatedPose {
    pub(crate) fn new(models: &[Transform]) -> AnimatedPose {
        AnimatedPose(RwLock::new(Inner {
            locals: vec![Transform::IDENTITY; models.len()],
            models: models.to_vec(),
            complete: true,
        }))
    }

    fn inner(&mut self) -> &mut Inner {
        self.0.get_mut().unwrap_or_else(PoisonError::into_inner)
    }

    /// This frame's animated models, complete.
    pub(crate) fn set_models(&mut self, models: &[Transform]) {
        let inner = self.inner();
        inner.models.copy_from_slice(models);
        inner.complete = true;
    }

    /// This frame's animated locals; the models are composed when first asked for.
    pub(crate) fn set_locals(&mut self, locals: &[Transform]) {
        let inner = self.inner();
        inner.locals.copy_from_slice(locals);
        inner.complete = false;
    }

    /// The animated model pose (composed now if the frame left it to be).
    pub(crate) fn models(&self, sk: &Skeleton) -> AnimatedModels<'_> {
        {
            let read = self.0.read().unwrap_or_else(PoisonError::into_inner);
            if read.complete {
                return AnimatedModels(read);
            }
        }
        {
            let mut write = self.0.write().unwrap_or_else(PoisonError::into_inner);
            if !write.complete {
                let Inner { locals, models, .. } = &mut *write;
                crate::pose::local_to_model_into(sk, locals, models);
                write.complete = true;
            }
        }
        AnimatedModels(self.0.read().unwrap_or_else(PoisonError::into_inner))
    }
}

impl Clone for AnimatedPose {
    fn clone(&self) -> AnimatedPose {
        let inner = self.0.read().unwrap_or_else(PoisonError::into_inner);
        AnimatedPose(RwLock::new(inner.clone()))
    }
}

/// The animated (input) model pose of a character's last frame, model space: a slice
/// (`Deref<Target = [Transform]>`), borrowed from the character
/// ([`crate::CharacterSim::animated_models`]).
#[derive(Debug)]
pub struct AnimatedModels<'a>(RwLockReadGuard<'a, Inner>);

impl Deref for AnimatedModels<'_> {
    type Target = [Transform];

    fn deref(&self) -> &[Transform] {
        &self.0.models
    }
}
