//! Tassel outside Rust: the **flat frame API** ([`FlatCharacter`]: buffers in, buffers
//! out, no glam or Tassel type across it) and the **C ABI** over it ([`abi`], declared in
//! `include/tassel.h`; the library is `libtassel_ffi.so` / `.a`, and `tassel_ffi.wasm`
//! built for `wasm32-unknown-unknown`, which the three.js package in `web/` loads).
//!
//! One frame of a character, whatever the engine:
//! 1. load it once from the bytes of its GLB/VRM/glTF file, with a rig file's text for
//!    chains, springs, cloths and ropes (optional for a VRM) and a mode (`fixed`, `spec`,
//!    `three-vrm`, `classic`);
//! 2. map the engine's bones to its joints: every node of the file is a joint, in the
//!    file's node order, with a name and a parent;
//! 3. each frame, hand it the character's world transform and the animated local
//!    transform of every joint (10 floats each: `tx ty tz qx qy qz qw sx sy sz`) and the
//!    frame time; take back the simulated locals (only the simulated joints change).
//!
//! The same solver code runs here as in Rust and Bevy; no second implementation.

pub mod abi;
mod crowd;
mod flat;

pub use crowd::FlatCrowd;
pub use flat::{parse_mode, FlatCharacter, FLOATS_PER_COLLIDER, FLOATS_PER_JOINT, MAX_RIG_BYTES};
