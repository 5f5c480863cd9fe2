//! The one error type of the core crate.

use thiserror::Error;

/// Everything the core library can reject. Each variant names what is wrong.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A skeleton with no joints.
    #[error("skeleton has no joints")]
    EmptySkeleton,
    /// More joints than the `u16` parent indices can hold.
    #[error("skeleton has {0} joints; at most {max} are supported", max = crate::limits::MAX_JOINTS)]
    TooManyJoints(usize),
    /// Two joints share a name.
    #[error("duplicate joint name '{0}'")]
    DuplicateName(String),
    /// A parent index that is not before its child.
    #[error("joint {joint} ('{name}') has parent {parent}, which is not before it")]
    ParentOutOfOrder {
        /// The joint's index.
        joint: usize,
        /// The joint's name.
        name: String,
        /// The offending parent index.
        parent: usize,
    },
    /// A parent reference to a joint that does not exist.
    #[error("joint '{name}' names parent {parent}, which does not exist")]
    MissingParent {
        /// The joint's name.
        name: String,
        /// The missing parent reference.
        parent: usize,
    },
    /// Parent links that loop.
    #[error("joints form a cycle through '{0}'")]
    Cycle(String),
    /// A rest transform or other input with NaN or infinity.
    #[error("non-finite value in {0}")]
    NonFinite(String),
    /// Buffers whose lengths do not match the skeleton.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which buffer.
        what: &'static str,
        /// What the skeleton needs.
        expected: usize,
        /// What was given.
        got: usize,
    },
    /// A bone name that the skeleton does not have.
    #[error("{context}: no bone named '{name}'")]
    MissingBone {
        /// Where the name was used (e.g. `chain 'tail' root`).
        context: String,
        /// The missing name.
        name: String,
    },
    /// A parameter outside its allowed range.
    #[error("{0}")]
    InvalidParameter(String),
    /// A rig file that does not parse.
    #[error("rig file: {0}")]
    RigParse(String),
    /// A time step that is NaN, negative or infinite.
    #[error("invalid time step {0} s: it must be finite and not negative")]
    InvalidTimeStep(f32),
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = core::result::Result<T, E>;
