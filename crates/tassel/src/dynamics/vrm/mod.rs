//! VRM spring bones (`VRMC_springBone` 1.0, its extended colliders, and VRM 0.x
//! `secondaryAnimation`), run by the specification's algorithm.
//!
//! - [`VrmSpringBones`]: the file's springs, joints and colliders as plain data (the
//!   `tassel-gltf` crate reads them from a `.vrm`).
//! - [`VrmLimit`]: a joint's swing limit (`VRMC_springBone_limit`, draft 1.0: cone, hinge,
//!   spherical), applied after inertia and after each collider push in every mode.
//! - [`VrmRig`]: compiled for a skeleton; [`VrmState`]: one character's tails;
//!   [`VrmJob`]: one frame.
//! - [`VrmMode::Spec`] runs the update once per frame exactly as the specification and
//!   UniVRM do; [`VrmMode::ThreeVrm`] as three-vrm 3.5.5 does in a web app (the bone
//!   length re-measured against last frame's tail); [`VrmMode::Fixed`] runs it at a fixed
//!   rate (its output the step that ends on the frame, else an output step carrying the
//!   last step to the frame's time), so that the look does not change with the frame rate.
//!
//! ```
//! use tassel::dynamics::vrm::*;
//! use tassel::{SkeletonBuilder, Transform, Pose};
//! use glam::Vec3;
//! let mut b = SkeletonBuilder::new();
//! b.add("root", None, Transform::IDENTITY);
//! b.add("hair", Some(0), Transform::from_translation(Vec3::new(0.0, 1.5, 0.0)));
//! let (skeleton, _) = b.build().unwrap();
//! let bones = VrmSpringBones {
//!     springs: vec![VrmSpring {
//!         name: "hair".into(),
//!         joints: vec![VrmJoint {
//!             joint: 1,
//!             tail: VrmTail::Local(Vec3::new(0.0, 0.0, 0.2)),
//!             gravity_power: 1.0,
//!             stiffness: 0.0,
//!             ..Default::default()
//!         }],
//!         ..Default::default()
//!     }],
//!     ..Default::default()
//! };
//! let rig = VrmRig::new(&skeleton, &bones, VrmOptions::default()).unwrap();
//! let mut state = VrmState::new(&rig);
//! let mut pose = Pose::rest(&skeleton);
//! for _ in 0..600 {
//!     pose.locals.copy_from_slice(skeleton.rest());
//!     pose.update_models(&skeleton, &Transform::IDENTITY).unwrap();
//!     VrmJob {
//!         skeleton: &skeleton, rig: &rig, state: &mut state,
//!         component: Transform::IDENTITY, dt: 1.0 / 60.0,
//!         locals: &mut pose.locals, models: &mut pose.models,
//!     }
//!     .run()
//!     .unwrap();
//! }
//! // With no stiffness the hair falls to hang straight down.
//! let tail = pose.models[1].transform_point(Vec3::new(0.0, 0.0, 0.2));
//! assert!((tail - Vec3::new(0.0, 1.3, 0.0)).length() < 1e-3);
//! ```

mod collide;
mod compile;
mod constraint;
mod job;
pub(crate) mod lanes;
mod limit;
mod settings;

pub use collide::PlacedVrmCollider;
pub use compile::{VrmLink, VrmRig};
pub use constraint::{ConstraintKind, NodeConstraint};
pub use job::{VrmJob, VrmState};
pub use limit::{axis_rotation, LinkLimit, VrmLimit, VrmLimitShape};
pub use settings::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmMode, VrmOptions, VrmShape, VrmSpring,
    VrmSpringBones, VrmStepping, VrmTail,
};
