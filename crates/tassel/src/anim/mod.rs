//! Animation: clips with translation, rotation and scale channels, sampled by the glTF
//! rules (STEP, LINEAR, CUBICSPLINE), and simple pose blending.

mod animator;
mod blend;
mod blend_space;
mod clip;
mod root_motion;
mod sample;
mod state_machine;

pub use animator::Animator;
pub use blend::{blend_locals, make_additive, BlendJob, BlendLayer, JointAccumulator};
pub use blend_space::{BlendSpace1D, BlendSpacePhase};
pub use clip::{Channel, Clip, Interpolation, JointTrack};
pub use root_motion::RootMotion;
pub use sample::{Playback, SamplingCursor, SamplingJob};
pub use state_machine::{BlendPlan, ParamKind, PlanLayer, StateMachine, StateMachineState};
