//! Pose blending.

use crate::math::Transform;

/// Blends `b` into `a` with weight `w` (0: `a`, 1: `b`): translation and scale lerp,
/// rotation shortest-path slerp. Writes into `out`.
pub fn blend_locals(a: &[Transform], b: &[Transform], w: f32, out: &mut [Transform]) {
    for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
        *o = x.lerp(y, w);
    }
}
