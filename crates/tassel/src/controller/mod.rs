//! A kinematic character controller on parry3d: the character's capsule moved through a
//! static [`Level`] by collide-and-slide, with auto-stepping, slope limits, snapping to the
//! ground and depenetration. The controller owns the character's world position; its
//! [`Movement`] (grounded, sliding, slope) feeds the locomotion state machine.
//!
//! ```
//! use glam::Vec3;
//! use tassel::controller::{CharacterCapsule, ControllerSettings, Level, LevelCollider, LevelShape};
//! use tassel::Transform;
//!
//! let level = Level::new(vec![LevelCollider::new(
//!     "floor",
//!     LevelShape::Box { half_extents: Vec3::new(10.0, 0.5, 10.0) },
//!     Vec3::new(0.0, -0.5, 0.0),
//! )])
//! .unwrap();
//! let capsule = CharacterCapsule::with_height(1.8, 0.3);
//! let settings = ControllerSettings::default();
//! // Falling from 1 m: the floor stops the capsule a skin's width above it.
//! let pose = Transform::from_translation(Vec3::new(0.0, 1.9, 0.0));
//! let m = settings
//!     .move_shape(&level, &capsule, &pose, Vec3::new(0.0, -2.0, 0.0), 1.0 / 60.0)
//!     .unwrap();
//! assert!(m.grounded);
//! assert!((pose.translation.y + m.translation.y - (0.9 + settings.skin)).abs() < 1e-3);
//! ```

mod carry;
mod level;
mod move_shape;
mod narrow;
mod segment_query;
mod settings;

pub use level::{Level, LevelCollider, LevelContact, LevelHit, LevelShape, RayHit, DEFAULT_GROUPS};
pub use move_shape::{ControllerHit, Movement};
pub use settings::{CharacterCapsule, ControllerSettings};
