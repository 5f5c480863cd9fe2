//! Animation: clips with translation, rotation and scale channels, sampled by the glTF
//! rules (STEP, LINEAR, CUBICSPLINE), and simple pose blending.

mod blend;
mod clip;
mod sample;

pub use blend::{blend_locals, make_additive, BlendJob, BlendLayer, JointAccumulator};
pub use clip::{Channel, Clip, Interpolation, JointTrack};
pub use sample::{Playback, SamplingCursor, SamplingJob};
