//! `move_shape`: collide-and-slide of the character's capsule through a [`Level`], with
//! auto-stepping (seed 003: lift, sweep forward, drop), slope limits, snapping to the
//! ground and depenetration.
//!
//! One call, in order:
//! 0. **Moving colliders** (moved since [`Level::start_frame`]): the one the character
//!    stood on carries it (and turns it about `up`); one that swept into it pushes it along
//!    its own motion (`carry`).
//! 1. **Keep the skin**: a capsule inside geometry, or closer to it than `skin`, is pushed
//!    out to the skin gap (straight up off walkable ground and step edges, along the
//!    normal otherwise).
//! 2. **Ground at the start** (contacts within two skins): stepping and snapping only
//!    happen for a character that stood on walkable ground.
//! 3. **Collide and slide**: sweep the remaining motion; stop `skin` short of the first
//!    contact (measured along its normal); re-aim the rest along the contact, per surface
//!    kind (walkable floor, steep slope, wall, ceiling); corners keep the crease direction;
//!    a low steep obstacle met while grounded is first tried as a step.
//! 4. **Snap** down onto walkable ground within `snap_to_ground` when the character was
//!    grounded and is not moving up; keep the skin again.
//! 5. **Ground at the end**: `grounded`, `sliding` and the ground normal.

use super::carry;
use super::level::{segment, Level, LevelContact, LevelHit};
use super::settings::{CharacterCapsule, ControllerSettings};
use crate::error::{Error, Result};
use crate::math::Transform;
use glam::{Quat, Vec3};

/// One contact met during a move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerHit {
    /// Index of the level collider.
    pub collider: usize,
    /// Contact point on the collider, world space.
    pub point: Vec3,
    /// Unit contact normal, world space, from the collider towards the character.
    pub normal: Vec3,
    /// When in the frame, seconds from its start (the share of the desired motion already
    /// travelled, times `dt`).
    pub time: f32,
}

/// What one [`ControllerSettings::move_shape`] call did.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Movement {
    /// The translation actually applied (add it to the pose's translation), metres.
    pub translation: Vec3,
    /// Standing on walkable ground at the end of the move.
    pub grounded: bool,
    /// On a slope at least `min_slide_angle` steep that it cannot stand on.
    pub sliding: bool,
    /// The ground's surface normal under the character at the end, if any ground is within
    /// reach (walkable or not).
    pub ground_normal: Option<Vec3>,
    /// A step was climbed during this move.
    pub stepped: bool,
    /// The character was pulled down onto the ground (walking down stairs or a slope).
    pub snapped: bool,
    /// The part of `translation` spent, before moving, getting out of geometry the capsule
    /// started inside (or back to the skin gap from closer).
    pub depenetration: Vec3,
    /// Contacts met, in order.
    pub hits: Vec<ControllerHit>,
    /// The moving collider that carried the character this frame (it stood on it when the
    /// frame began); its motion is part of `translation`.
    pub platform: Option<usize>,
    /// How much that platform turned the character about `up` this frame: apply it to
    /// the character's facing (identity without a turning platform).
    pub platform_rotation: Quat,
}

impl Movement {
    /// The slope under the character, degrees from horizontal, measured against `up`.
    pub fn slope_angle(&self, up: Vec3) -> Option<f32> {
        let up = up.normalize_or(Vec3::Y);
        self.ground_normal
            .map(|n| n.dot(up).clamp(-1.0, 1.0).acos().to_degrees())
    }
}

/// Ground found under the capsule.
#[derive(Debug, Clone, Copy)]
struct Ground {
    distance: f32,
    normal: Vec3,
    walkable: bool,
}

struct Mover<'a> {
    level: &'a Level,
    mask: u32,
    radius: f32,
    half_height: f32,
    rotation: Quat,
    s: &'a ControllerSettings,
    up: Vec3,
    cos_climb: f32,
    cos_slide: f32,
    bottom: f32,
}

/// Removes the part of `v` that goes into a plane of normal `n`.
fn clip(v: Vec3, n: Vec3) -> Vec3 {
    let d = v.dot(n);
    if d < 0.0 {
        v - n * d
    } else {
        v
    }
}

impl Mover<'_> {
    fn cast(&self, pos: Vec3, t: Vec3) -> Option<LevelHit> {
        if t.length_squared() < 1e-18 {
            return None;
        }
        let (a, b) = segment(pos, self.rotation, self.half_height);
        self.level.cast(a, b, self.radius, t, self.mask)
    }

    fn vertical(&self, v: Vec3) -> Vec3 {
        self.up * v.dot(self.up)
    }

    fn walkable(&self, n: Vec3) -> bool {
        n.dot(self.up) >= self.cos_climb - 1e-5
    }

    /// The surface under a contact: a short ray just beyond the contact point, on the side
    /// away from the capsule's axis. On a flat floor or a slope it returns the contact's
    /// own surface; on a step edge it finds the step's top, which the rounded contact
    /// normal alone would call a steep slope.
    fn surface_normal(&self, pos: Vec3, hit: &LevelHit) -> Option<Vec3> {
        let off = hit.point - pos;
        let away = (off - self.vertical(off)).normalize_or_zero();
        let lift = self.s.skin.max(0.01);
        let origin = hit.point + away * 0.005 + self.up * lift;
        self.level
            .ray_masked(origin, -self.up, 3.0 * lift, self.mask)
            .map(|r| r.normal)
    }

    /// A steep contact that is really the edge of walkable ground: low on the capsule
    /// (within a step's height of its bottom), facing up, with a walkable surface just
    /// beyond it. Returns that surface's normal.
    fn edge_floor(&self, pos: Vec3, hit: &LevelHit) -> Option<Vec3> {
        let rise = hit.normal.dot(self.up);
        if self.walkable(hit.normal) || rise <= 1e-4 {
            return None;
        }
        let height = (hit.point - pos).dot(self.up) + self.bottom;
        if height > self.s.max_step_height + self.s.skin {
            return None;
        }
        self.surface_normal(pos, hit).filter(|&n| self.walkable(n))
    }

    /// What a contact `distance` away is to stand on: walkable by its own normal, a step's
    /// edge (walkable, with the surface beyond as its normal), or not walkable.
    fn classify(&self, pos: Vec3, hit: &LevelHit, distance: f32) -> Ground {
        if self.walkable(hit.normal) {
            return Ground {
                distance,
                normal: hit.normal,
                walkable: true,
            };
        }
        match self.edge_floor(pos, hit) {
            Some(normal) => Ground {
                distance,
                normal,
                walkable: true,
            },
            None => Ground {
                distance,
                normal: hit.normal,
                walkable: false,
            },
        }
    }

    /// How far the capsule must rise, after moving `horizontal`, for its lower sphere to
    /// stay a skin's width from the edge point `edge` (capped at the step height).
    fn roll_over(&self, pos: Vec3, horizontal: Vec3, edge: Vec3) -> f32 {
        let (a, b) = segment(pos, self.rotation, self.half_height);
        let centre = if a.dot(self.up) <= b.dot(self.up) {
            a
        } else {
            b
        } + horizontal;
        let to_edge = edge - centre;
        let dh = (to_edge - self.vertical(to_edge)).length();
        let reach = self.radius + self.s.skin;
        if dh >= reach {
            return 0.0;
        }
        let need = to_edge.dot(self.up) + (reach * reach - dh * dh).sqrt();
        need.clamp(0.0, self.s.max_step_height)
    }

    /// The ground the capsule stands on: the contacts within two skins that face up,
    /// walkable ones (or step edges) first, the most level of them.
    fn support(&self, pos: Vec3, scratch: &mut Vec<LevelContact>) -> Option<Ground> {
        let (a, b) = segment(pos, self.rotation, self.half_height);
        self.level.contacts(
            a,
            b,
            self.radius,
            2.0 * self.s.skin + 1e-3,
            self.mask,
            scratch,
        );
        let mut best: Option<Ground> = None;
        for c in scratch.iter() {
            let rise = c.normal.dot(self.up);
            if rise <= 1e-4 {
                continue;
            }
            let hit = LevelHit {
                collider: c.collider,
                fraction: 0.0,
                point: c.point,
                normal: c.normal,
            };
            let g = self.classify(pos, &hit, c.distance);
            let better = match &best {
                None => true,
                Some(o) => {
                    (g.walkable && !o.walkable)
                        || (g.walkable == o.walkable
                            && g.normal.dot(self.up) > o.normal.dot(self.up))
                }
            };
            if better {
                best = Some(g);
            }
        }
        best
    }

    /// Sweeps down by `reach` and classifies what is there.
    fn ground(&self, pos: Vec3, reach: f32) -> Option<Ground> {
        let hit = self.cast(pos, -self.up * reach)?;
        Some(self.classify(pos, &hit, hit.fraction * reach))
    }

    /// Pushes the capsule out of anything closer than the skin: straight up off walkable
    /// ground and step edges (so that standing on a slope does not creep down it, and
    /// walking down stairs does not speed up), along the contact normal otherwise. The deepest contact first, a few rounds.
    fn keep_skin(&self, mut pos: Vec3, scratch: &mut Vec<LevelContact>) -> Vec3 {
        let skin = self.s.skin;
        for _ in 0..2 * self.s.iterations.max(4) {
            let (a, b) = segment(pos, self.rotation, self.half_height);
            self.level
                .contacts(a, b, self.radius, skin - 1e-4, self.mask, scratch);
            let Some(c) = scratch
                .iter()
                .min_by(|x, y| x.distance.total_cmp(&y.distance))
            else {
                break;
            };
            let deficit = skin - c.distance;
            let rise = c.normal.dot(self.up);
            // A step's edge under the capsule is ground too: pushing out along its rounded
            // normal, which leans forward, would speed up a character walking down stairs.
            let on_edge = || {
                let hit = LevelHit {
                    collider: c.collider,
                    fraction: 0.0,
                    point: c.point,
                    normal: c.normal,
                };
                rise >= 0.2 && self.edge_floor(pos, &hit).is_some()
            };
            pos += if self.walkable(c.normal) || on_edge() {
                self.up * (deficit / rise)
            } else {
                c.normal * deficit
            };
        }
        pos
    }

    /// Seed 003's auto-step: lift by the step height, sweep the horizontal motion forward,
    /// drop back down. Returns where the character lands and how far it got forward.
    fn try_step(&self, pos: Vec3, horizontal: Vec3, hit: &LevelHit) -> Option<(Vec3, f32)> {
        let s = self.s;
        let len = horizontal.length();
        if s.max_step_height <= 0.0 || len < 1e-6 {
            return None;
        }
        // Only obstacles whose contact is low enough can be steps.
        let height = (hit.point - pos).dot(self.up) + self.bottom;
        if height > s.max_step_height + s.skin {
            return None;
        }
        let lift = match self.cast(pos, self.up * s.max_step_height) {
            Some(h) => (h.fraction * s.max_step_height - s.skin).max(0.0),
            None => s.max_step_height,
        };
        if lift < 1e-4 {
            return None;
        }
        let lifted = pos + self.up * lift;
        let dir = horizontal / len;
        let need = len + s.min_step_width;
        let free = match self.cast(lifted, dir * need) {
            Some(h) => {
                let dn = (-h.normal.dot(dir)).max(1e-3);
                h.fraction * need - s.skin / dn
            }
            None => need,
        };
        let forward = len.min(free - s.min_step_width);
        if forward <= 1e-5 {
            return None;
        }
        let ahead = lifted + dir * forward;
        let drop = lift + 2.0 * s.skin;
        let down = self.cast(ahead, -self.up * drop)?;
        let fall = (down.fraction * drop - s.skin).max(0.0);
        let landed = ahead - self.up * fall;
        let climb = (landed - pos).dot(self.up);
        if climb < -s.skin || climb > s.max_step_height + 1e-4 {
            return None;
        }
        let under = self.ground(landed, 2.0 * s.skin + 1e-3)?;
        if !under.walkable {
            return None;
        }
        Some((landed, forward))
    }
}

impl ControllerSettings {
    /// Moves `capsule`, whose centre and orientation are `pose` (scale ignored; the capsule
    /// axis is the pose's local Y), through `level` by `desired` metres this frame of `dt`
    /// seconds. Gravity and jumping are the caller's: add them to `desired`.
    ///
    /// Errors (naming the value) for a NaN or infinite pose, motion or `dt`, a negative
    /// `dt`, or invalid settings or capsule. Never panics on user data.
    pub fn move_shape(
        &self,
        level: &Level,
        capsule: &CharacterCapsule,
        pose: &Transform,
        desired: Vec3,
        dt: f32,
    ) -> Result<Movement> {
        let mut out = Movement::default();
        self.move_shape_into(level, capsule, pose, desired, dt, &mut out)?;
        Ok(out)
    }

    /// [`ControllerSettings::move_shape`] into `out`, whose `hits` buffer is reused: once
    /// it and this thread's contact buffer have grown to what the level needs, a call
    /// allocates nothing (a game keeps one `Movement` per character). On error `out` is
    /// left as it was.
    pub fn move_shape_into(
        &self,
        level: &Level,
        capsule: &CharacterCapsule,
        pose: &Transform,
        desired: Vec3,
        dt: f32,
        out: &mut Movement,
    ) -> Result<()> {
        CONTACTS.with_borrow_mut(|scratch| {
            scratch.clear();
            self.move_with(level, capsule, pose, desired, dt, out, scratch)
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn move_with(
        &self,
        level: &Level,
        capsule: &CharacterCapsule,
        pose: &Transform,
        desired: Vec3,
        dt: f32,
        out: &mut Movement,
        scratch: &mut Vec<LevelContact>,
    ) -> Result<()> {
        self.validate()?;
        capsule.validate()?;
        if !dt.is_finite() || dt < 0.0 {
            return Err(Error::InvalidTimeStep(dt));
        }
        if !pose.translation.is_finite() || !pose.rotation.is_finite() {
            return Err(Error::NonFinite("controller pose".into()));
        }
        if !desired.is_finite() {
            return Err(Error::NonFinite(format!("desired translation {desired}")));
        }
        let up = self.up.normalize();
        let rotation = if pose.rotation.length() > 1e-6 {
            pose.rotation.normalize()
        } else {
            Quat::IDENTITY
        };
        let m = Mover {
            level,
            mask: self.collide_with,
            radius: capsule.radius,
            half_height: capsule.half_height,
            rotation,
            s: self,
            up,
            cos_climb: self.max_climb_angle.to_radians().cos(),
            cos_slide: self.min_slide_angle.to_radians().cos(),
            bottom: capsule.half_total_height(),
        };
        let start = pose.translation;
        let mut hits = std::mem::take(&mut out.hits);
        hits.clear();
        *out = Movement {
            hits,
            ..Movement::default()
        };
        // Colliders moved this frame: the platform under the character carries it, the
        // others push it along their motion where they swept into it.
        let carried = carry::follow(
            level,
            &carry::Body {
                radius: m.radius,
                half_height: m.half_height,
                rotation,
                up,
                cos_climb: m.cos_climb,
                skin: self.skin,
                mask: self.collide_with,
            },
            start,
        );
        out.platform = carried.platform;
        out.platform_rotation = carried.turn;
        let mut pos = m.keep_skin(carried.pos, scratch);
        out.depenetration = pos - carried.pos;

        let was_grounded = m.support(pos, scratch).is_some_and(|g| g.walkable);

        // Collide and slide.
        let total = desired.length();
        let mut travelled = 0.0f32;
        let mut remaining = desired;
        let mut planes: [Vec3; 4] = [Vec3::ZERO; 4];
        let mut plane_count = 0usize;
        for _ in 0..self.iterations {
            let len = remaining.length();
            if len < 1e-7 {
                break;
            }
            let Some(hit) = m.cast(pos, remaining) else {
                pos += remaining;
                break;
            };
            let dir = remaining / len;
            let n = hit.normal;
            let approach = -dir.dot(n);
            // Stop `skin` short of the contact along its normal (never move backwards).
            let advance = if approach > 1e-6 {
                (hit.fraction * len - self.skin / approach).max(0.0)
            } else {
                0.0
            };
            pos += dir * advance;
            travelled += advance;
            remaining = dir * (len - advance);
            out.hits.push(ControllerHit {
                collider: hit.collider,
                point: hit.point,
                normal: n,
                time: if total > 0.0 {
                    travelled / total * dt
                } else {
                    0.0
                },
            });

            let rise = n.dot(up);
            let horizontal = remaining - m.vertical(remaining);
            let edge = m.edge_floor(pos, &hit).is_some();
            // A steep obstacle met while grounded and walked into: try it as a step.
            if was_grounded && !edge && rise < m.cos_climb && rise > -0.1 && horizontal.dot(n) < 0.0
            {
                if let Some((landed, forward)) = m.try_step(pos, horizontal, &hit) {
                    pos = landed;
                    out.stepped = true;
                    let hlen = horizontal.length();
                    remaining = horizontal * ((hlen - forward) / hlen).max(0.0);
                    continue;
                }
            }

            // Re-aim the rest of the motion along the contact.
            let (next, plane) = if rise <= 1e-4 {
                // Wall or ceiling: slide along it.
                (clip(remaining, n), n)
            } else {
                let vertical = m.vertical(remaining);
                let v = if vertical.dot(up) > 0.0 || (!edge && rise <= m.cos_slide + 1e-5) {
                    // Moving up, or on a slope steep enough to slide down: follow it.
                    clip(vertical, n)
                } else {
                    // Standing: a gentler slope or a step's edge holds the character.
                    Vec3::ZERO
                };
                let into = -horizontal.dot(n);
                if m.walkable(n) {
                    // Up a walkable slope at the same horizontal speed.
                    let climb = if into > 0.0 {
                        up * (into / rise)
                    } else {
                        Vec3::ZERO
                    };
                    (v + horizontal + climb, n)
                } else if edge {
                    // Walking into the edge of a low step: the rounded bottom rolls over
                    // it, kept a skin's width from the edge point.
                    if into > 0.0 {
                        out.stepped = true;
                        (
                            v + horizontal + up * m.roll_over(pos, horizontal, hit.point),
                            n,
                        )
                    } else {
                        (v + horizontal, n)
                    }
                } else {
                    // Too steep to climb: its horizontal part blocks like a wall.
                    let wall = (n - up * rise).normalize_or(n);
                    (v + clip(horizontal, wall), wall)
                }
            };
            remaining = next;
            // A corner: keep only the crease direction; a third plane stops the motion.
            for k in 0..plane_count {
                let p = planes[k];
                if remaining.dot(p) < -1e-6 {
                    let crease = p.cross(plane).normalize_or_zero();
                    remaining = crease * crease.dot(remaining);
                    if (0..plane_count).any(|j| j != k && remaining.dot(planes[j]) < -1e-6) {
                        remaining = Vec3::ZERO;
                    }
                    break;
                }
            }
            if plane_count < planes.len() {
                planes[plane_count] = plane;
                plane_count += 1;
            } else {
                planes.rotate_left(1);
                planes[planes.len() - 1] = plane;
            }
        }

        // Snap down onto the ground when walking off a step or over a crest.
        if was_grounded && !out.stepped && desired.dot(up) <= 1e-6 && self.snap_to_ground > 0.0 {
            let here = m.support(pos, scratch);
            if !here.is_some_and(|g| g.walkable) {
                if let Some(g) = m.ground(pos, self.snap_to_ground + self.skin) {
                    if g.walkable {
                        pos -= up * (g.distance - self.skin).max(0.0);
                        out.snapped = true;
                    }
                }
            }
        }
        pos = m.keep_skin(pos, scratch);

        if let Some(g) = m.support(pos, scratch) {
            out.ground_normal = Some(g.normal);
            out.grounded = g.walkable;
            let rise = g.normal.dot(up);
            out.sliding = rise > 1e-4 && rise <= m.cos_slide + 1e-5;
        }
        out.translation = pos - start;
        Ok(())
    }
}

thread_local! {
    /// The contact buffer of every `move_shape` call on this thread, kept between calls so
    /// that a call allocates nothing once it has grown.
    static CONTACTS: std::cell::RefCell<Vec<LevelContact>> =
        const { std::cell::RefCell::new(Vec::new()) };
}
