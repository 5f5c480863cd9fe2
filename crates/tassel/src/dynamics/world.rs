//! World collision of chains, cloths and ropes: simulated points kept out of a [`Level`]
//! (the controller's static world), swept so that fast bones do not pass through thin
//! walls, and sliding along what they touch. After KawaiiPhysics' `bAllowWorldCollision`
//! (seed 000): each bone is a sphere of its `radius` against the world's geometry.

use crate::controller::Level;
use crate::math::Transform;
use glam::Vec3;

/// The world as one step of one solver sees it: the level, and the transform of the
/// solver's space at the start (`from`: where the points' previous positions are
/// expressed) and at the end of the step (`to`: where the new positions are); the
/// identity for solvers in world space (cloths, ropes).
#[derive(Clone, Copy)]
pub(crate) struct WorldContact<'a> {
    pub level: &'a Level,
    pub from: Transform,
    pub to: Transform,
}

impl WorldContact<'_> {
    /// Only when some level geometry lies within `reach` of the chain's root at either
    /// end of the step (`root_before` in `from`'s space, `root_after` in `to`'s): every
    /// point of a chain stays within its length of the root, so a chain away from all
    /// geometry costs one BVH query per step.
    pub fn near(&self, root_before: Vec3, root_after: Vec3, reach: f32) -> bool {
        let a = self.from.transform_point(root_before);
        let b = self.to.transform_point(root_after);
        self.level.touches_aabb(a.min(b) - reach, a.max(b) + reach)
    }

    /// Only when some level geometry lies within the box `min`–`max` (world space) grown
    /// by `margin`: one BVH query for a whole cloth or rope per step.
    pub fn near_box(&self, min: Vec3, max: Vec3, margin: f32) -> bool {
        self.level.touches_aabb(min - margin, max + margin)
    }

    /// `x` (step space) whose previous position was `prev` (previous step's space), kept
    /// `r` out of the level: a step that meets a surface stops there and keeps the
    /// tangential part of the rest of its motion; what is still inside is pushed out.
    pub fn resolve(&self, x: Vec3, prev: Vec3, r: f32) -> Vec3 {
        let a = self.from.transform_point(prev);
        let b0 = self.to.transform_point(x);
        let mut b = b0;
        let v = b - a;
        if v.length_squared() > 0.0 {
            if let Some(hit) = self.level.cast(a, a, r, v, u32::MAX) {
                let contact = a + v * hit.fraction;
                let rest = b - contact;
                b = contact + rest - hit.normal * rest.dot(hit.normal).min(0.0);
            }
        }
        b = push_out(self.level, b, r);
        if b == b0 {
            x
        } else {
            self.to.inverse_transform_point(b)
        }
    }
}

/// `p` pushed out of every level primitive it is closer to than `r` (a few rounds for
/// corners), world space.
pub(crate) fn push_out(level: &Level, mut p: Vec3, r: f32) -> Vec3 {
    for _ in 0..4 {
        match level.deepest_contact(p, r) {
            Some((depth, normal)) if depth > 0.0 => p += normal * depth,
            _ => break,
        }
    }
    p
}

/// The world-space points `points` of a solver whose `free(i)` holds, each `radius(i)`,
/// kept out of `level`: one BVH query around their bounds (now and at the step's start,
/// `prev`; none when `prev` is `None`), then each point swept from `prev` and sliding
/// (or, without `prev`, pushed out). `moved(i, push)` is told of every point that moved.
pub(crate) fn collide_points(
    level: &Level,
    pos: &mut [Vec3],
    prev: Option<&[Vec3]>,
    points: std::ops::Range<usize>,
    free: impl Fn(usize) -> bool,
    radius: impl Fn(usize) -> f32,
    mut moved: impl FnMut(usize, Vec3),
) {
    let (mut min, mut max, mut r) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0.0f32);
    for i in points.clone().filter(|&i| free(i)) {
        min = min.min(pos[i]);
        max = max.max(pos[i]);
        if let Some(prev) = prev {
            min = min.min(prev[i]);
            max = max.max(prev[i]);
        }
        r = r.max(radius(i));
    }
    let world = WorldContact {
        level,
        from: Transform::IDENTITY,
        to: Transform::IDENTITY,
    };
    if min.x > max.x || !world.near_box(min, max, r + 1e-3) {
        return;
    }
    for i in points.filter(|&i| free(i)) {
        let before = pos[i];
        let after = match prev {
            Some(prev) => world.resolve(before, prev[i], radius(i)),
            None => push_out(level, before, radius(i)),
        };
        if after != before {
            pos[i] = after;
            moved(i, after - before);
        }
    }
}
