//! Mass-spring bone cloth after SPCRJointDynamics (seed 004): a grid of points on several
//! parallel bone chains (fixed points, virtual tips), structural, shear and bending
//! constraints with separate shrink and stretch strengths, resistance, hardness, gravity,
//! wind, drag and lift, fixed-rate steps with iterations, point, segment and quad
//! collision with friction, an angle limit, a final length limit, teleport reset and
//! write-back of bone rotations.
//!
//! [`ClothRig`] is compiled once from the rig's `[[cloth]]` tables; [`ClothState`] is
//! the per-character state; [`ClothJob`] runs one frame. The simulation runs in world
//! space, so the character's own motion moves the cloth by inertia.

pub(crate) mod compile;
pub(crate) mod contact;
mod job;
pub(crate) mod lanes;
pub(crate) mod settings;
pub(crate) mod spcr;

pub use compile::{ClothConstraint, ClothRig, ConstraintKind};
pub use job::{ClothJob, ClothState};
pub use settings::{
    ClothMode, ClothSettings, ClothWind, CollisionSwitches, ConstraintSwitches, PointCurves,
    StrengthCurves, SurfaceCollision,
};
