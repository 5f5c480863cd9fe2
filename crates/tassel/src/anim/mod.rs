//! Animation: clips with translation, rotation and scale channels, sampled by the glTF
//! rules (STEP, LINEAR, CUBICSPLINE), and simple pose blending.

mod blend;
mod clip;

pub use blend::blend_locals;
pub use clip::{Channel, Clip, Interpolation, JointTrack};
