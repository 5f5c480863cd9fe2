//! The limits on what Tassel accepts, in one place (the README's limits table quotes
//! them). Each keeps memory and time proportional to real work: a single number in a
//! file, a rig or an argument cannot ask for gigabytes or hours. Going past one is an
//! error that names the entry and the limit, never a hang, an abort or a panic.

/// The most joints (glTF nodes) one skeleton may hold (parents are `u16`, with
/// `u16::MAX` for none).
pub const MAX_JOINTS: usize = 16_384;

/// The latest key time of a clip, seconds (one hour). A bake or a render of a clip plays
/// every frame of it, so this bounds their work.
pub const MAX_CLIP_SECONDS: f32 = 3600.0;

/// The largest coordinate (metres, or the file's unit) of a rest-pose translation or a
/// translation key, and the largest scale factor. f32 keeps 6 mm steps at 1e5 and 6 cm at
/// 1e6; beyond that a bone length or a squared distance loses all meaning.
pub const MAX_COORDINATE: f32 = 1.0e6;

/// The most fixed steps any solver takes in one frame (`max_steps_per_frame`); a longer
/// hitch drops time instead of stalling the frame.
pub const MAX_STEPS_PER_FRAME: u32 = 64;

/// The shortest fixed time step any solver accepts, seconds (10 kHz).
pub const MIN_TIME_STEP: f32 = 1.0e-4;

/// The most warm-up steps a chain takes when it starts (`warmup_steps`).
pub const MAX_WARMUP_STEPS: u32 = 10_000;

/// The most colliders one rig file, or one file's VRM spring bones, may define.
pub const MAX_COLLIDERS: usize = 4_096;

/// The most chains, springs, cloths or ropes (each) one rig file may define, and the most
/// VRM springs one file may hold.
pub const MAX_SOLVERS: usize = 4_096;

/// The most parameters, states or transitions (each) one state machine may define.
pub const MAX_STATES: usize = 4_096;

/// The most (simulated point, collider) pairs a character's chains or VRM springs may
/// test per step (4 M): what a rig costs per frame, and what its compiled form holds.
pub const MAX_COLLIDER_PAIRS: usize = 1 << 22;

/// The most constraint iterations a cloth or a rope's particle world runs per step.
pub const MAX_ITERATIONS: u32 = 1_000;

/// The most bone constraints (`[[bone_constraint]]` pairs after patterns, dummy tips'
/// included) one rig may compile to.
pub const MAX_BONE_CONSTRAINTS: usize = 1 << 16;

/// The most bone-constraint solves (constraints × iterations before and after collision)
/// a character's chains run per step.
pub const MAX_CONSTRAINT_SOLVES: usize = 1 << 20;

/// The most external forces (`[[external_force]]` tables) one rig may define.
pub const MAX_EXTERNAL_FORCES: usize = 256;
