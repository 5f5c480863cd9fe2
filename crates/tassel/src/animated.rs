//! The animated (input) model pose a [`crate::CharacterSim`] keeps for its callers, composed
//! only when asked for on frames whose solvers did not need it whole.

use crate::math::Transform;
use crate::skeleton::Skeleton;
use std::ops::Deref;
use std::sync::{Mutex, MutexGuard, PoisonError};

/// The last frame's animated model pose: complete, or the animated locals to compose it
/// from on first use. Behind a lock so that [`AnimatedPose::models`] can finish it through
/// a shared reference (the character stays `Send + Sync`); the frame itself writes through
/// `&mut` and never locks.
#[derive(Debug, Default)]
pub(crate) struct AnimatedPose(Mutex<Inner>);

#[derive(Debug, Default, Clone)]
struct Inner {
    locals: Vec<Transform>,
    models: Vec<Transform>,
    complete: bool,
}

impl AnimatedPose {
    pub(crate) fn new(models: &[Transform]) -> AnimatedPose {
        AnimatedPose(Mutex::new(Inner {
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
        let mut inner = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        if !inner.complete {
            let Inner { locals, models, .. } = &mut *inner;
            crate::pose::local_to_model_into(sk, locals, models);
            inner.complete = true;
        }
        AnimatedModels(inner)
    }
}

impl Clone for AnimatedPose {
    fn clone(&self) -> AnimatedPose {
        let inner = self.0.lock().unwrap_or_else(PoisonError::into_inner);
        AnimatedPose(Mutex::new(inner.clone()))
    }
}

/// The animated (input) model pose of a character's last frame, model space: a slice
/// (`Deref<Target = [Transform]>`), borrowed from the character
/// ([`crate::CharacterSim::animated_models`]).
#[derive(Debug)]
pub struct AnimatedModels<'a>(MutexGuard<'a, Inner>);

impl Deref for AnimatedModels<'_> {
    type Target = [Transform];

    fn deref(&self) -> &[Transform] {
        &self.0.models
    }
}
