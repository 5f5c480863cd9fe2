//! The VRM specification's collision per lane: [`crate::dynamics::vrm::PlacedVrmCollider`]'s
//! distance, push and settling with its operations, so that every lane gets the scalar
//! bits. Shared by [`super::VrmCrowd`] (a lane per character) and the single character's
//! springs side by side ([`super::springs`]).

use crate::dynamics::vrm::{LinkLimit, VrmShape};
use crate::lanes::{closest_point_on_segment, differs, Lane, Mask, F, LANES, M, Q, V3};
use glam::Vec3;

/// A collider placed in world space, per lane: `a` (centre, capsule head, plane point) and
/// `b` (capsule tail, plane normal), with a bounding sphere for the quick rejection: every
/// point of a sphere or capsule's axis lies within `half` of `mid`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Placed<T = F> {
    pub(crate) a: V3<T>,
    pub(crate) b: V3<T>,
    pub(crate) mid: V3<T>,
    pub(crate) half: T,
}

impl<T: Lane> Placed<T> {
    #[inline(always)]
    pub(crate) fn of(p: &Placed) -> Placed<T> {
        Placed {
            a: V3::of(p.a),
            b: V3::of(p.b),
            mid: V3::of(p.mid),
            half: T::of(p.half),
        }
    }

    #[inline(always)]
    pub(crate) fn f(&self) -> Placed {
        Placed {
            a: self.a.f(),
            b: self.b.f(),
            mid: self.mid.f(),
            half: self.half.f(),
        }
    }
}

/// The specification's signed distance per lane
/// ([`crate::dynamics::vrm::PlacedVrmCollider::collision`]) with the vector it is measured
/// along, or `None` when no lane of `lanes` (the lanes whose result the caller uses) can
/// be in contact.
///
/// The early `None` compares against a bounding sphere rounded outward, so it only ever
/// skips what the exact test would find out of contact: the results keep the scalar bits.
#[inline(always)]
pub(crate) fn distance<T: Lane>(
    shape: &VrmShape,
    placed: &Placed<T>,
    p: V3<T>,
    r: T,
    lanes: T::M,
) -> Option<(T, V3<T>)> {
    let zero = T::splat(0.0);
    let (radius, inside) = match *shape {
        VrmShape::Sphere { radius, inside, .. } | VrmShape::Capsule { radius, inside, .. } => {
            (radius, inside)
        }
        VrmShape::Plane { .. } => {
            return Some(((p - placed.a).dot(placed.b) - r, placed.b));
        }
    };
    if !inside {
        // Certainly out of reach: farther from the bounding sphere's centre than its
        // radius plus the contact distance, with 1e-4 to spare for the rounding of these
        // few operations (so that no lane the exact test would push is skipped).
        let reach = (placed.half + (T::splat(radius) + r)) * T::splat(1.0001) + T::splat(1e-6);
        let far = (p - placed.mid).dot(p - placed.mid).gt(reach * reach);
        if far.or(lanes.not()) == <T::M as Mask>::ALL {
            return None;
        }
    }
    let delta = match *shape {
        VrmShape::Capsule { .. } => {
            let (a, b) = (placed.a, placed.b);
            let axis = b - a;
            let delta = p - a;
            let dot = axis.dot(delta);
            let len2 = axis.dot(axis);
            let beyond = delta - axis;
            let along = delta - axis * (dot / len2);
            V3::select(dot.le(zero), delta, V3::select(len2.le(dot), beyond, along))
        }
        _ => p - placed.a,
    };
    let len = delta.length();
    Some(if inside {
        ((T::splat(radius) - r) - len, delta)
    } else {
        (len - (T::splat(radius) + r), delta)
    })
}

/// The push of the specification's collision: `None` when no lane of `lanes` is in contact,
/// else the direction, the signed distance and the lanes in contact (of `lanes` and maybe
/// others). The direction (three divisions and a square root) is computed only when a lane
/// is in contact.
#[inline(always)]
pub(crate) fn contact<T: Lane>(
    shape: &VrmShape,
    placed: &Placed<T>,
    p: V3<T>,
    r: T,
    lanes: T::M,
) -> Option<(V3<T>, T, T::M)> {
    let (dist, delta) = distance(shape, placed, p, r, lanes)?;
    let hit = dist.lt(T::splat(0.0));
    if !hit.any() {
        return None;
    }
    let dir = match *shape {
        VrmShape::Plane { .. } => delta,
        VrmShape::Sphere { inside, .. } | VrmShape::Capsule { inside, .. } => {
            let dir = delta.normalize_or(V3::splat(Vec3::ZERO));
            if inside {
                -dir
            } else {
                dir
            }
        }
    };
    Some((dir, dist, hit))
}

/// How far a tail at `p` violates the collider, per lane (≤ 0: not at all), or `None` when
/// no lane of `lanes` can.
#[inline(always)]
pub(crate) fn penetration<T: Lane>(
    shape: &VrmShape,
    placed: &Placed<T>,
    p: V3<T>,
    r: T,
    lanes: T::M,
) -> Option<T> {
    distance(shape, placed, p, r, lanes).map(|(d, _)| -d)
}

/// [`crate::dynamics::vrm::PlacedVrmCollider::settle`] per lane, or `None` where it
/// keeps the tail of every lane of `lanes` (the lanes whose result is used).
#[inline(always)]
pub(crate) fn settle_one<T: Lane>(
    shape: &VrmShape,
    placed: &Placed<T>,
    pos: V3<T>,
    length: T,
    tail: V3<T>,
    r: T,
    lanes: T::M,
) -> Option<V3<T>> {
    let zero = T::splat(0.0);
    let one = T::splat(1.0);
    let (a, c, valid) = match *shape {
        VrmShape::Plane { .. } => {
            let normal = placed.b;
            let c = (r - (pos - placed.a).dot(normal)) / length;
            (normal, c, <T::M as Mask>::ALL)
        }
        VrmShape::Sphere { radius, inside, .. } | VrmShape::Capsule { radius, inside, .. } => {
            let q = match *shape {
                VrmShape::Capsule { .. } => closest_point_on_segment(tail, placed.a, placed.b),
                _ => placed.a,
            };
            let limit = if inside {
                (T::splat(radius) - r).max(T::splat(0.0))
            } else {
                T::splat(radius) + r
            };
            let d = pos - q;
            let dl = d.length();
            let k = (limit * limit - dl * dl - length * length) / (T::splat(2.0) * length * dl);
            let valid = dl.lt(T::splat(1e-9)).not();
            if inside {
                (-d / dl, -k, valid)
            } else {
                (d / dl, k, valid)
            }
        }
    };
    let u = (tail - pos).normalize_or(a);
    let ua = u.dot(a);
    let keep = (c - T::splat(1e-6)).le(ua).or(c.lt(T::splat(-1.0)));
    let unchanged = length.le(zero).or(valid.not()).or(keep);
    if !lanes.and(unchanged.not()).any() {
        return None;
    }
    let straight = pos + a * length;
    let side = (u - a * ua).normalize_or(a.any_orthonormal());
    let turned = pos + (a * c + side * (one - c * c).sqrt()) * length;
    let moved = V3::select(T::splat(1.0).le(c), straight, turned);
    Some(V3::select(unchanged, tail, moved))
}

/// The specification's collision (one push per collider and the projection back to
/// the bone length), then with `exact` the settling of what is left inside. Returns
/// the tail and the lanes where a collider acted. `colliders` are indices into `shapes`
/// and `placed` (the link's list); `r` is the tail radius per lane. With `masks` (one per
/// collider), collider `k` acts only on the lanes of `masks[k]`: lanes whose links have
/// different lists, each the in-order sublist of `colliders` its mask picks, get the
/// scalar bits of their own list.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn collide_tail<T: Lane>(
    colliders: &[usize],
    masks: Option<&[M]>,
    shapes: &[(usize, VrmShape)],
    placed: &[Placed],
    r: T,
    position: V3<T>,
    length: T,
    rest_dir: V3<T>,
    mut tail: V3<T>,
    exact: bool,
    limit: Option<(&LinkLimit, Q<T>)>,
) -> (V3<T>, T::M) {
    let mut acted = <T::M as Mask>::NONE;
    // Per lane, the entry of the last collider that pushed it (-1: none).
    let mut last = T::splat(-1.0);
    let only = |k: usize| masks.map(|m| <T::M as Mask>::of(m[k]));
    let every = <T::M as Mask>::ALL;
    for (k, &c) in colliders.iter().enumerate() {
        let shape = &shapes[c].1;
        let pl = Placed::<T>::of(&placed[c]);
        if let Some((dir, dist, hit)) = contact(shape, &pl, tail, r, only(k).unwrap_or(every)) {
            let hit = match only(k) {
                Some(m) => hit.and(m),
                None => hit,
            };
            let pushed = position + (tail - dir * dist - position).normalize_or(rest_dir) * length;
            tail = V3::select(hit, pushed, tail);
            acted = acted.or(hit);
            last = T::select(hit, T::splat(k as f32), last);
            if let Some((lim, parent_r)) = limit {
                tail = limit_lanes(lim, parent_r, position, tail, length, hit);
            }
        }
    }
    let before_settling = tail;
    // A lane where no collider acted kept its tail, at which every collider's distance
    // was found not negative: no penetration to settle (the scalar settling's first pass
    // changes nothing and stops). So with no lane acted, the settling is skipped.
    //
    // The first pass asks about a collider only for the lanes that can be inside it:
    // those pushed by it or a later entry (a lane's tail has not moved since the entries
    // after its last push found it outside them), and those this pass moved already; a
    // collider whose bounding sphere is out of their reach is not tested at all.
    //
    // The second pass runs for the lanes the first changed (a lane the first left as it
    // was meets every collider at the same tail again, so the same decisions), and of
    // those it asks an entry only about the lanes that can decide otherwise than in the
    // first pass: the entries before the one that moved a lane last (they saw another
    // tail), that entry itself only where its tail was still inside it (its depth there
    // is known: the first pass measured it at this very tail), and every entry for the
    // lanes this pass moved. The entries after it saw this tail in the first pass and
    // left it.
    if exact && acted.any() {
        let zero = T::splat(0.0);
        let out_of_reach = T::splat(f32::NEG_INFINITY);
        let mut first = <T::M as Mask>::NONE;
        // Per lane, the entry that moved it last in the first pass and its depth there.
        let mut moved_at = T::splat(-1.0);
        let mut depth = zero;
        for (k, &c) in colliders.iter().enumerate() {
            let shape = &shapes[c].1;
            let pl = Placed::<T>::of(&placed[c]);
            let kk = T::splat(k as f32);
            let asked = kk.le(last).or(first);
            let lanes = match only(k) {
                Some(m) => asked.and(m),
                None => asked,
            };
            let Some(before) = penetration(shape, &pl, tail, r, lanes) else {
                continue;
            };
            // (Only the lanes asked about: the others would change nothing here.)
            let inside = zero.lt(before).and(lanes);
            if !inside.any() {
                continue;
            }
            let (t, moved, after) =
                settle_lanes(shape, &pl, position, length, tail, r, before, inside);
            tail = t;
            first = first.or(moved);
            moved_at = T::select(moved, kk, moved_at);
            depth = T::select(moved, after, depth);
        }
        acted = acted.or(first);
        if first.any() {
            let mut second = <T::M as Mask>::NONE;
            for (k, &c) in colliders.iter().enumerate() {
                let shape = &shapes[c].1;
                let pl = Placed::<T>::of(&placed[c]);
                let kk = T::splat(k as f32);
                let mut asked = first.and(kk.lt(moved_at)).or(second);
                let same = first.and(second.not()).and(kk.ne(moved_at).not());
                let mut known = same.and(zero.lt(depth));
                if let Some(m) = only(k) {
                    asked = asked.and(m);
                    known = known.and(m);
                }
                if !asked.or(known).any() {
                    continue;
                }
                let measured = if asked.any() {
                    penetration(shape, &pl, tail, r, asked).unwrap_or(out_of_reach)
                } else {
                    out_of_reach
                };
                let before = T::select(known, depth, measured);
                let inside = zero.lt(before).and(asked.or(known));
                if !inside.any() {
                    continue;
                }
                let (t, moved, _) =
                    settle_lanes(shape, &pl, position, length, tail, r, before, inside);
                tail = t;
                second = second.or(moved);
            }
            acted = acted.or(second);
        }
        if let Some((lim, parent_r)) = limit {
            let moved = differs(tail, before_settling);
            tail = limit_lanes(lim, parent_r, position, tail, length, moved);
        }
    }
    (tail, acted)
}

/// One settling of the lanes `inside` (whose depth is `before`) on a collider: the tail,
/// new where it is less deep; the lanes it moved; the depth of the new tail (minus
/// infinity where out of reach). A function, not a closure: a closure would not be
/// compiled with the target features of the update that inlines it.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn settle_lanes<T: Lane>(
    shape: &VrmShape,
    pl: &Placed<T>,
    position: V3<T>,
    length: T,
    tail: V3<T>,
    r: T,
    before: T,
    inside: T::M,
) -> (V3<T>, T::M, T) {
    let Some(t) = settle_one(shape, pl, position, length, tail, r, inside) else {
        // Every lane inside keeps its tail: its depth is `before` again, no better.
        return (tail, <T::M as Mask>::NONE, before);
    };
    // (`None`: every lane inside is now out of reach, so less deep.)
    let after = penetration(shape, pl, t, r, inside).unwrap_or(T::splat(f32::NEG_INFINITY));
    let better = inside.and(after.lt(before));
    (
        V3::select(better, t, tail),
        better.and(differs(t, tail)),
        after,
    )
}

/// [`LinkLimit::apply`] on the lanes in `lanes`, lane by lane with the scalar code (the
/// scalar bits; limits are rare enough that their trigonometry need not be in lanes).
#[inline(always)]
pub(crate) fn limit_lanes<T: Lane>(
    lim: &LinkLimit,
    parent_r: Q<T>,
    position: V3<T>,
    tail: V3<T>,
    length: T,
    lanes: T::M,
) -> V3<T> {
    let m = lanes.m();
    if !m.any() {
        return tail;
    }
    let (r, p, t, len) = (parent_r.f(), position.f(), tail.f(), length.f());
    let mut out = t;
    for l in 0..LANES {
        if m.get(l) {
            out.set(l, lim.apply(r.get(l), p.get(l), t.get(l), len.get(l)));
        }
    }
    V3::of(out)
}

impl Default for Placed {
    fn default() -> Placed {
        let zero = V3::splat(Vec3::ZERO);
        Placed {
            a: zero,
            b: zero,
            mid: zero,
            half: F::splat(0.0),
        }
    }
}
