//! The colliders as SPCR keeps them (swept from the last frame's place across the
//! iterations) and its contact tests: points pushed straight out, segments, triangles.

use super::ue::{
    lerp, normalized, safe_normal, ue_clamp, CAPSULE_EPS_SQ, CAPSULE_MIN_HEIGHT, ENTER_MIN, EPS_SQ,
};
use crate::collide::{PlacedCollider, Shape};
use glam::{DVec3, Vec3};

#[inline]
pub(super) fn d3(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

/// A collider as SPCR keeps it: a sphere, or a capsule from its −Y end along its full
/// axis, each with its place at the last frame's end, before this iteration and now.
/// Other shapes act on points only, where they are this frame.
#[derive(Debug, Clone, Copy)]
pub(crate) enum SpcrCollider {
    Round {
        capsule: bool,
        radius: f64,
        height: f64,
        pos: DVec3,
        dir: DVec3,
        pos_prev: DVec3,
        dir_prev: DVec3,
        pos_frame: DVec3,
        dir_frame: DVec3,
    },
    Other(PlacedCollider),
}

/// A round collider where a (sub-)iteration sees it: `pos` and `dir` a share `delta` of
/// the way from its place before the iteration to its place now (SPCR lerps both at
/// every use), its radius widened by the point's.
#[derive(Clone, Copy)]
struct Swept {
    capsule: bool,
    radius: f64,
    height: f64,
    pos: DVec3,
    dir: DVec3,
}

impl SpcrCollider {
    /// The collider as a contact test sees it at share `delta` of the iteration, for a
    /// point of radius `extra`; `None` for the shapes SPCR has not.
    fn swept(&self, delta: f64, extra: f64) -> Option<Swept> {
        match *self {
            SpcrCollider::Round {
                capsule,
                radius,
                height,
                pos,
                dir,
                pos_prev,
                dir_prev,
                ..
            } => Some(Swept {
                capsule,
                radius: radius + extra,
                height,
                pos: lerp(pos_prev, pos, delta),
                dir: lerp(dir_prev, dir, delta),
            }),
            SpcrCollider::Other(_) => None,
        }
    }

    /// SPCR's place of `col` this frame: (capsule, radius, height, position, direction).
    fn target(col: &PlacedCollider) -> Option<(bool, f64, f64, DVec3, DVec3)> {
        match col.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => Some((
                false,
                radius.into(),
                0.0,
                d3(col.transform.translation),
                DVec3::ZERO,
            )),
            Shape::Capsule { radius, length } if f64::from(length) > CAPSULE_MIN_HEIGHT => {
                let (a, b) = col.capsule_ends(length);
                let (a, b) = (d3(a), d3(b));
                Some((true, radius.into(), length.into(), a, b - a))
            }
            Shape::Capsule { radius, .. } => Some((
                false,
                radius.into(),
                0.0,
                d3(col.transform.translation),
                DVec3::ZERO,
            )),
            _ => None,
        }
    }

    /// At reset (`InitializeColliderPositionOld`): everything at this frame's place.
    pub(super) fn reset(col: &PlacedCollider) -> SpcrCollider {
        match Self::target(col) {
            Some((capsule, radius, height, p, d)) => SpcrCollider::Round {
                capsule,
                radius,
                height,
                pos: p,
                dir: d,
                pos_prev: p,
                dir_prev: d,
                pos_frame: p,
                dir_frame: d,
            },
            None => SpcrCollider::Other(*col),
        }
    }

    /// `UpdateColliders`: a share `delta` of the way from the last frame's place to this
    /// frame's, the place before kept for the sub-iterations.
    pub(super) fn sweep(&mut self, col: &PlacedCollider, delta: f64) {
        match (Self::target(col), &mut *self) {
            (
                Some((capsule, r, h, p, d)),
                SpcrCollider::Round {
                    capsule: c,
                    radius,
                    height,
                    pos,
                    dir,
                    pos_prev,
                    dir_prev,
                    pos_frame,
                    dir_frame,
                },
            ) => {
                *c = capsule;
                *radius = r;
                *height = h;
                *pos_prev = *pos;
                *pos = lerp(*pos_frame, p, delta);
                if capsule {
                    *dir_prev = *dir;
                    *dir = lerp(*dir_frame, d, delta);
                }
            }
            _ => *self = SpcrCollider::reset(col),
        }
    }

    /// `UpdateColliderInfoAtEnd`.
    pub(super) fn end_frame(&mut self, col: &PlacedCollider) {
        match self {
            SpcrCollider::Round {
                pos,
                dir,
                pos_frame,
                dir_frame,
                ..
            } => {
                *pos_frame = *pos;
                *dir_frame = *dir;
            }
            SpcrCollider::Other(c) => *c = *col,
        }
    }
}

pub(super) fn triangle_centre([a, b, c]: [DVec3; 3]) -> DVec3 {
    let ab = lerp(a, b, 0.5);
    let ac = lerp(a, c, 0.5);
    lerp(ab, ac, 0.5)
}

/// `PushoutFromSphere`.
fn push_from_sphere(centre: DVec3, radius: f64, p: DVec3) -> DVec3 {
    let d = p - centre;
    let sq = d.length_squared();
    if sq > EPS_SQ && sq < radius * radius {
        centre + d * radius / sq.sqrt()
    } else {
        p
    }
}

/// `PushoutFromCollider` for a point of radius `extra` (SPCR's points have none).
pub(super) fn push_point(col: &SpcrCollider, p: DVec3, extra: f64, delta: f64) -> DVec3 {
    let Some(c) = col.swept(delta, extra) else {
        let SpcrCollider::Other(c) = col else {
            return p;
        };
        let q = p.as_vec3();
        return d3(c.resolve(q, q, extra as f32));
    };
    if !c.capsule {
        return push_from_sphere(c.pos, c.radius, p);
    }
    let n = normalized(c.dir);
    let along = n.dot(p - c.pos);
    if along <= 0.0 {
        push_from_sphere(c.pos, c.radius, p)
    } else if along >= c.height {
        push_from_sphere(c.pos + c.dir, c.radius, p)
    } else {
        let on = c.pos + n * along;
        let out = p - on;
        let sq = out.length_squared();
        if sq > CAPSULE_EPS_SQ && sq < c.radius * c.radius {
            on + out * c.radius / sq.sqrt()
        } else {
            p
        }
    }
}

/// `CollisionDetection_Sphere`: (point on the segment, the centre, radius) if they meet.
fn sphere_segment(centre: DVec3, radius: f64, p1: DVec3, p2: DVec3) -> (bool, DVec3, DVec3) {
    let d = p2 - p1;
    let len = d.length();
    let dir = d / len;
    let dot = dir.dot(centre - p1);
    let on_line = dir * ue_clamp(dot, 0.0, len) + p1;
    (
        (centre - on_line).length_squared() <= radius * radius,
        on_line,
        centre,
    )
}

/// `CollisionDetection`: where segment `p1`–`p2` meets a round collider, as SPCR finds
/// it: (point on the segment, point on the collider, radius). A segment of no length
/// meets nothing here (SPCR divides by its length).
pub(super) fn segment_contact(
    col: &SpcrCollider,
    p1: DVec3,
    p2: DVec3,
    extra: f64,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let c = col.swept(delta, extra)?;
    if (p2 - p1).length_squared() == 0.0 {
        return None;
    }
    let (radius, base, axis) = (c.radius, c.pos, c.dir);
    if !c.capsule {
        let (hit, on_line, on_col) = sphere_segment(base, radius, p1, p2);
        return hit.then_some((on_line, on_col, radius));
    }
    for centre in [base, base + axis] {
        let (hit, on_line, on_col) = sphere_segment(centre, radius, p1, p2);
        if hit {
            return Some((on_line, on_col, radius));
        }
    }
    // `ComputeNearestPoints` of the two lines.
    let seg = p2 - p1;
    let n1 = axis.cross(seg.cross(axis));
    let n2 = seg.cross(axis.cross(seg));
    let t1 = (p1 - base).dot(n2) / axis.dot(n2);
    let t2 = (base - p1).dot(n1) / seg.dot(n1);
    let sq = ((p1 + seg * t2) - (base + axis * t1)).length_squared();
    if sq > radius * radius {
        return None;
    }
    let (t1, t2) = (ue_clamp(t1, 0.0, 1.0), ue_clamp(t2, 0.0, 1.0));
    let on_col = base + axis * t1;
    let on_line = p1 + seg * t2;
    ((on_col - on_line).length_squared() <= radius * radius).then_some((on_line, on_col, radius))
}

/// `SimpleRaycast` against the plane `n·x + dist = 0`.
fn raycast(origin: DVec3, dir: DVec3, n: DVec3, dist: f64) -> Option<f64> {
    let v = dir.dot(n);
    let o = -origin.dot(n) - dist;
    if v.abs() <= 0.001 {
        return None;
    }
    let enter = o / v;
    (enter > ENTER_MIN).then_some(enter)
}

fn triangle_contains([a, b, c]: [DVec3; 3], p: DVec3) -> bool {
    let (ap, bp, cp) = (a - p, b - p, c - p);
    let u = ap.cross(bp);
    let v = bp.cross(cp);
    let w = cp.cross(ap);
    !(u.dot(v) < 0.0 || v.dot(w) < 0.0)
}

/// `CheckCollision` of `UpdateSurfaceCollision`: (intersection, push, radius) when a
/// round collider is within its radius of the triangle. `pull` is SPCR's
/// `SurfaceColliderType` PUSH (a capsule through the cloth's middle is cast along its
/// axis); else OFF.
pub(super) fn surface_contact(
    col: &SpcrCollider,
    tri: [DVec3; 3],
    extra: f64,
    pull: bool,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let swept = col.swept(delta, extra)?;
    let (capsule, radius, col_pos, col_dir) = (swept.capsule, swept.radius, swept.pos, swept.dir);
    let [a, b, c] = tri;
    let col_n = safe_normal(col_dir);
    let centre = triangle_centre(tri);
    let to_col = normalized(col_pos - centre);
    let mut normal = normalized(safe_normal(b - a).cross(safe_normal(c - a)));
    let plane = -normal.dot(a);
    normal = -normal;
    let side_dot = to_col.dot(normal);
    let inverse = -normal;
    let within = |on_col: DVec3, hit: DVec3| (on_col - hit).length_squared() <= radius * radius;
    if capsule {
        let side = col_n.dot(normal) * side_dot;
        let towards = normalized(normal * side_dot * -1.0);
        let start = if side < 0.0 {
            col_pos + (col_dir * 0.5) * 2.0
        } else {
            col_pos
        };
        if let Some(enter) = raycast(start, towards, inverse, plane) {
            let hit = start + towards * enter;
            if triangle_contains(tri, hit) {
                return within(start, hit).then_some((hit, hit - start, radius));
            }
        } else if pull {
            // A capsule through the cloth's middle: cast along its axis.
            let on_col = col_pos;
            let end = col_pos + (col_dir * 0.5) * 2.0;
            if let Some(enter) = raycast(on_col, col_dir, inverse, plane) {
                let hit = on_col + col_dir * enter;
                if triangle_contains(tri, hit) {
                    let to_end = end - on_col;
                    let to_hit = hit - on_col;
                    let point_dot = (end - hit).dot(to_hit);
                    let line_dot = to_end.dot(to_end);
                    if !(point_dot >= 0.0 && point_dot <= line_dot) {
                        return None;
                    }
                    let ce = to_end.dot(to_hit);
                    let back = on_col + safe_normal(to_end) * -radius;
                    let push = hit - back;
                    let on_axis = on_col + to_end * (ce / line_dot);
                    return within(on_axis, hit).then_some((hit, push, radius));
                }
            }
        }
        None
    } else {
        let towards = normal * side_dot * -1.0;
        let enter = raycast(col_pos, towards, inverse, plane)?;
        let hit = col_pos + towards * enter;
        (triangle_contains(tri, hit) && within(col_pos, hit)).then_some((
            hit,
            hit - col_pos,
            radius,
        ))
    }
}
