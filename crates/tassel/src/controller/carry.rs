//! What moving colliders do to a character before it moves itself: the one it stands on
//! carries it (translation, and the turn about `up`), the others push it along their own
//! motion when they swept into it during the frame, so that a closing door pushes the
//! character out in front of it, never through it.
//!
//! Both use one identity: a collider's motion over the frame is the rigid map
//! `D = to · from⁻¹`, and the capsule at `p` stood against the collider's start-of-frame
//! pose exactly as the capsule at `D(p)` stands against its pose now. So both tests run
//! against the collider as it is, with no copy of its old geometry.

use super::level::{segment, Level};
use crate::math::Transform;
use glam::{Quat, Vec3};

/// The capsule and the settings the carry and the push need.
pub(super) struct Body {
    pub radius: f32,
    pub half_height: f32,
    pub rotation: Quat,
    pub up: Vec3,
    /// Cosine of the steepest walkable slope.
    pub cos_climb: f32,
    pub skin: f32,
    pub mask: u32,
}

/// The outcome: where the character is now, what carried it and how much it turned.
pub(super) struct Carried {
    pub pos: Vec3,
    pub platform: Option<usize>,
    pub turn: Quat,
}

/// The rigid motion of collider `id` over the frame, as a map of world points.
fn motion(level: &Level, id: usize) -> Option<Transform> {
    let (from, to) = level.motion(id)?;
    Some(to * from.inverse())
}

/// The part of `q` that turns about `up` (swing–twist decomposition).
fn twist_about(q: Quat, up: Vec3) -> Quat {
    let v = Vec3::new(q.x, q.y, q.z);
    let p = up * v.dot(up);
    let t = Quat::from_xyzw(p.x, p.y, p.z, q.w);
    if t.length_squared() < 1e-12 {
        Quat::IDENTITY
    } else {
        t.normalize()
    }
}

/// Applies the frame's collider motions to the character at `pos`.
pub(super) fn follow(level: &Level, body: &Body, pos: Vec3) -> Carried {
    let mut out = Carried {
        pos,
        platform: None,
        turn: Quat::IDENTITY,
    };
    let Some(_) = level.moved().next() else {
        return out;
    };
    // Carry: the moved collider the capsule stood on at the start of the frame (within two
    // skins, on a walkable face); the most level one when several are.
    let mut best: Option<(usize, Transform, f32)> = None;
    for id in level.moved() {
        if level.groups_of(id) & body.mask == 0 {
            continue;
        }
        let Some(d) = motion(level, id) else { continue };
        let (a, b) = segment(d.transform_point(pos), body.rotation, body.half_height);
        let Some(s) = level.separation_from(id, a, b, body.radius) else {
            continue;
        };
        // The normal is of the collider as it is now: turn it back for the test.
        let rise = (d.rotation.inverse() * s.normal).dot(body.up);
        let on_it = s.distance < 2.0 * body.skin + 1e-3 && rise >= body.cos_climb - 1e-5;
        if on_it && best.as_ref().is_none_or(|b| rise > b.2) {
            best = Some((id, d, rise));
        }
    }
    if let Some((id, d, _)) = best {
        out.pos = d.transform_point(pos);
        out.platform = Some(id);
        out.turn = twist_about(d.rotation, body.up);
    }
    // Push: a moved collider that was clear of the capsule at the start of the frame and
    // swept into it. Relative to the collider the capsule went from `D(p)` to `p`; where
    // that sweep meets the collider, the rest of the collider's motion takes the capsule
    // along.
    for id in level.moved() {
        if Some(id) == out.platform || level.groups_of(id) & body.mask == 0 {
            continue;
        }
        let Some(d) = motion(level, id) else { continue };
        let before = d.transform_point(out.pos);
        let relative = out.pos - before;
        if relative.length_squared() < 1e-14 {
            continue;
        }
        let (a, b) = segment(before, body.rotation, body.half_height);
        if level
            .separation_from(id, a, b, body.radius)
            .is_none_or(|s| s.distance < 0.0)
        {
            continue; // already inside at the start: depenetration's job
        }
        if let Some((f, _)) = level.sweep_against(id, a, b, body.radius, relative) {
            out.pos -= relative * (1.0 - f.clamp(0.0, 1.0));
        }
    }
    out
}
