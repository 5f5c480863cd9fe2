//! Pose blending: two poses, or N weighted layers with per-joint masks and additive
//! layers.
//!
//! N-way blending is the seed's incremental form: blend B into A with normalised weights,
//! keep the running weight, then blend C into the result — which equals the plain weighted
//! average. Rotations are averaged as weighted quaternion sums, each quaternion first
//! flipped into the first one's hemisphere (so no blend takes the long way round), and
//! normalised at the end.

use crate::error::{Error, Result};
use crate::math::Transform;
use glam::{Quat, Vec3, Vec4};

/// Blends `b` into `a` with weight `w` (0: `a`, 1: `b`): translation and scale lerp,
/// rotation shortest-path slerp. Writes into `out`.
pub fn blend_locals(a: &[Transform], b: &[Transform], w: f32, out: &mut [Transform]) {
    for ((o, x), y) in out.iter_mut().zip(a).zip(b) {
        *o = x.lerp(y, w);
    }
}

/// The running blend of one joint: the weighted average so far and its total weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointAccumulator {
    /// Total weight so far.
    pub weight: f32,
    translation: Vec3,
    rotation: Vec4,
    scale: Vec3,
}

impl Default for JointAccumulator {
    fn default() -> Self {
        Self {
            weight: 0.0,
            translation: Vec3::ZERO,
            rotation: Vec4::ZERO,
            scale: Vec3::ZERO,
        }
    }
}

impl JointAccumulator {
    /// Blends `t` in with weight `w`: the result so far gets `weight / (weight + w)`,
    /// `t` gets `w / (weight + w)`.
    pub fn add(&mut self, t: &Transform, w: f32) {
        if w <= 0.0 {
            return;
        }
        let total = self.weight + w;
        let (ka, kb) = (self.weight / total, w / total);
        let mut q = Vec4::from(t.rotation);
        if self.weight > 0.0 && self.rotation.dot(q) < 0.0 {
            q = -q;
        }
        self.translation = self.translation * ka + t.translation * kb;
        self.rotation = self.rotation * ka + q * kb;
        self.scale = self.scale * ka + t.scale * kb;
        self.weight = total;
    }

    /// The blended transform (identity when nothing was added).
    pub fn result(&self) -> Transform {
        if self.weight <= 0.0 {
            return Transform::IDENTITY;
        }
        let q = Quat::from_vec4(self.rotation);
        let q = if q.length_squared() > 1e-12 {
            q.normalize()
        } else {
            Quat::IDENTITY
        };
        Transform::new(self.translation, q, self.scale)
    }
}

/// One input of a [`BlendJob`].
#[derive(Debug, Clone, Copy)]
pub struct BlendLayer<'a> {
    /// Local transforms, one per joint.
    pub locals: &'a [Transform],
    /// Layer weight (≥ 0).
    pub weight: f32,
    /// Optional per-joint weights multiplying `weight` (e.g. 1 on the upper body, 0 below).
    pub mask: Option<&'a [f32]>,
}

/// Blends N layers, then applies additive layers.
///
/// Per joint, where the normal layers' weights sum to less than 1, the rest pose fills the
/// missing weight (so a lone layer at weight 0.3 is 30 % of the way from rest). Additive
/// layers hold deltas made by [`make_additive`] and are applied on top, scaled by weight.
#[derive(Debug)]
pub struct BlendJob<'a> {
    /// The skeleton's rest pose.
    pub rest: &'a [Transform],
    /// Normal layers.
    pub layers: &'a [BlendLayer<'a>],
    /// Additive layers.
    pub additive: &'a [BlendLayer<'a>],
    /// Output.
    pub out: &'a mut [Transform],
}

impl BlendJob<'_> {
    /// Checks sizes and weights.
    pub fn validate(&self) -> Result<()> {
        let n = self.rest.len();
        if self.out.len() != n {
            return Err(Error::LengthMismatch {
                what: "blend output",
                expected: n,
                got: self.out.len(),
            });
        }
        for l in self.layers.iter().chain(self.additive) {
            if l.locals.len() != n {
                return Err(Error::LengthMismatch {
                    what: "blend layer",
                    expected: n,
                    got: l.locals.len(),
                });
            }
            if !(l.weight.is_finite() && l.weight >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "blend weight {} must be finite and ≥ 0",
                    l.weight
                )));
            }
            if let Some(m) = l.mask {
                if m.len() != n {
                    return Err(Error::LengthMismatch {
                        what: "blend mask",
                        expected: n,
                        got: m.len(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Validates, then blends. Never allocates.
    pub fn run(self) -> Result<()> {
        self.validate()?;
        for j in 0..self.rest.len() {
            let mut acc = JointAccumulator::default();
            for l in self.layers {
                let w = l.weight * l.mask.map_or(1.0, |m| m[j].max(0.0));
                acc.add(&l.locals[j], w);
            }
            if acc.weight < 1.0 {
                acc.add(&self.rest[j], 1.0 - acc.weight);
            }
            let mut t = acc.result();
            for l in self.additive {
                let w = l.weight * l.mask.map_or(1.0, |m| m[j].max(0.0));
                if w > 0.0 {
                    let d = &l.locals[j];
                    t.translation += d.translation * w;
                    t.rotation = (t.rotation * Quat::IDENTITY.slerp(d.rotation, w)).normalize();
                    t.scale *= Vec3::ONE.lerp(d.scale, w);
                }
            }
            self.out[j] = t;
        }
        Ok(())
    }
}

/// The additive delta of `pose` over `reference`, per joint: translation difference,
/// rotation `reference⁻¹ · pose`, scale ratio. Applying it at weight 1 to `reference` gives
/// `pose` back.
pub fn make_additive(pose: &[Transform], reference: &[Transform], out: &mut [Transform]) {
    for ((o, p), r) in out.iter_mut().zip(pose).zip(reference) {
        *o = Transform::new(
            p.translation - r.translation,
            (r.rotation.inverse() * p.rotation).normalize(),
            p.scale / r.scale,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(x: f32, angle: f32, s: f32) -> Transform {
        Transform::new(
            Vec3::new(x, 2.0 * x, -x),
            Quat::from_rotation_z(angle),
            Vec3::splat(s),
        )
    }

    #[test]
    fn incremental_equals_direct_weighted_average() {
        let (a, b, c) = (
            pose(1.0, 0.2, 1.0),
            pose(-2.0, 0.9, 2.0),
            pose(4.0, -0.4, 0.5),
        );
        let (wa, wb, wc) = (0.5, 0.3, 0.2);
        // The seed's incremental form, step by step.
        let mut acc = JointAccumulator::default();
        acc.add(&a, wa);
        acc.add(&b, wb);
        assert!((acc.weight - 0.8).abs() < 1e-6);
        acc.add(&c, wc);
        let inc = acc.result();
        // Direct, by hand: Σ wᵢ xᵢ / Σ wᵢ; rotation: normalised Σ wᵢ qᵢ.
        let t = (a.translation * wa + b.translation * wb + c.translation * wc) / 1.0;
        let s = (a.scale * wa + b.scale * wb + c.scale * wc) / 1.0;
        let q = (Vec4::from(a.rotation) * wa
            + Vec4::from(b.rotation) * wb
            + Vec4::from(c.rotation) * wc)
            .normalize();
        assert!(inc.translation.abs_diff_eq(t, 1e-6));
        assert!(inc.scale.abs_diff_eq(s, 1e-6));
        assert!(Vec4::from(inc.rotation).abs_diff_eq(q, 1e-6));
        // Same angle axis: the average angle is the weighted mean angle (to first order).
        let (axis, angle) = inc.rotation.to_axis_angle();
        assert!(axis.z > 0.99 && (angle - (0.5 * 0.2 + 0.3 * 0.9 - 0.2 * 0.4)).abs() < 0.01);
    }

    #[test]
    fn never_the_long_way_round() {
        // q and −q are the same rotation: blending them must give that rotation.
        let q = Quat::from_rotation_y(0.7);
        let mut acc = JointAccumulator::default();
        acc.add(&Transform::from_translation_rotation(Vec3::ZERO, q), 0.5);
        acc.add(&Transform::from_translation_rotation(Vec3::ZERO, -q), 0.5);
        assert!(acc.result().rotation.dot(q).abs() > 1.0 - 1e-6);
        let a = Transform::from_translation_rotation(Vec3::ZERO, Quat::from_rotation_y(0.1));
        let b = Transform::from_translation_rotation(Vec3::ZERO, -Quat::from_rotation_y(0.5));
        let mid = a.lerp(&b, 0.5);
        assert!(mid.rotation.dot(Quat::from_rotation_y(0.3)).abs() > 1.0 - 1e-6);
    }

    #[test]
    fn rest_fills_missing_weight_masks_and_additive() {
        let rest = [pose(0.0, 0.0, 1.0), pose(0.0, 0.0, 1.0)];
        let a = [pose(1.0, 0.0, 1.0), pose(1.0, 0.0, 1.0)];
        let mask = [1.0, 0.0];
        let mut out = [Transform::IDENTITY; 2];
        BlendJob {
            rest: &rest,
            layers: &[BlendLayer {
                locals: &a,
                weight: 0.25,
                mask: Some(&mask),
            }],
            additive: &[],
            out: &mut out,
        }
        .run()
        .unwrap();
        assert!(
            (out[0].translation.x - 0.25).abs() < 1e-6,
            "a quarter of the way from rest"
        );
        assert_eq!(out[1].translation.x, 0.0, "masked out");
        // Additive: the delta of b over a, applied fully to a, gives b.
        let b = [pose(3.0, 0.8, 2.0), pose(-1.0, -0.3, 0.5)];
        let mut delta = [Transform::IDENTITY; 2];
        make_additive(&b, &a, &mut delta);
        BlendJob {
            rest: &rest,
            layers: &[BlendLayer {
                locals: &a,
                weight: 1.0,
                mask: None,
            }],
            additive: &[BlendLayer {
                locals: &delta,
                weight: 1.0,
                mask: None,
            }],
            out: &mut out,
        }
        .run()
        .unwrap();
        for (o, want) in out.iter().zip(&b) {
            assert!(o.translation.abs_diff_eq(want.translation, 1e-5));
            assert!(o.rotation.dot(want.rotation).abs() > 1.0 - 1e-6);
            assert!(o.scale.abs_diff_eq(want.scale, 1e-5));
        }
        let bad = BlendJob {
            rest: &rest,
            layers: &[BlendLayer {
                locals: &a,
                weight: f32::NAN,
                mask: None,
            }],
            additive: &[],
            out: &mut out,
        };
        assert!(bad.run().is_err());
    }
}
