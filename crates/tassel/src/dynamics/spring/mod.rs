//! The spring controller after Unreal's AnimNode_SpringBone (seed 002): one bone on a
//! Hooke spring with damping, in world space, stepped at a fixed rate with the remaining
//! time carried over; the owner's velocity carries the bone along; an error-reset
//! threshold (teleport guard), a damping cut-off for stability, a displacement limit,
//! translation-axis filters and a rotation derived from the displacement with its own
//! axis filters.

mod settings;
mod solver;

pub use settings::SpringSettings;
pub use solver::{SpringJob, SpringRig, SpringState};
