//! The level the character controller moves through: colliders in a parry BVH, with the
//! queries the controller needs (capsule sweep, ray, contacts). Every collider is split into
//! primitives (a triangle mesh into its triangles), each a leaf of parry's BVH. Colliders
//! can be added, removed and moved between frames ([`edit`]): the BVH leaves are updated in
//! place, and a collider's motion during the frame is kept for the controller (moving
//! platforms carry, doors push).

mod edit;

use super::narrow::{Prim, Separation};
use crate::error::{Error, Result};
use glam::{Quat, Vec3};
use parry3d::bounding_volume::{Aabb, BoundingVolume};
use parry3d::partitioning::{Bvh, BvhBuildStrategy};

/// The geometry of one level collider, in its own frame.
#[derive(Debug, Clone, PartialEq)]
pub enum LevelShape {
    /// A box centred on its origin.
    Box {
        /// Half the size along each local axis, metres (> 0).
        half_extents: Vec3,
    },
    /// A sphere centred on its origin.
    Sphere {
        /// Radius, metres (> 0).
        radius: f32,
    },
    /// A capsule along the local Y axis, centred on its origin.
    Capsule {
        /// Half the length of the axis segment, metres (≥ 0).
        half_height: f32,
        /// Radius, metres (> 0).
        radius: f32,
    },
    /// A wedge: the base is the rectangle `x ∈ [-width/2, width/2]`, `z ∈ [0, length]` at
    /// `y = 0`; the top face rises from the edge `z = 0` to `y = height` at `z = length`,
    /// where a vertical back face closes it. Slope angle `atan(height / length)`.
    Ramp {
        /// Size across, metres (> 0).
        width: f32,
        /// Horizontal run, metres (> 0).
        length: f32,
        /// Rise, metres (> 0).
        height: f32,
    },
    /// Triangles (e.g. a mesh read from a glTF file), vertices in the collider's frame.
    /// Either side blocks; a mesh has no inside. Degenerate (zero-area) triangles are skipped.
    TriMesh {
        /// Vertex positions.
        vertices: Vec<Vec3>,
        /// Three vertex indices per triangle.
        indices: Vec<[u32; 3]>,
    },
}

impl LevelShape {
    /// A ramp of the given slope angle (degrees, in `(0, 90)`) rising over `length`.
    pub fn ramp_with_angle(width: f32, length: f32, angle_deg: f32) -> Self {
        LevelShape::Ramp {
            width,
            length,
            height: length * angle_deg.to_radians().tan(),
        }
    }
}

/// One collider of a level: a name (for errors and hit reports), a shape, where it is and
/// the collision groups it belongs to.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelCollider {
    /// A name for messages.
    pub name: String,
    /// The geometry, in the collider's frame.
    pub shape: LevelShape,
    /// World position of the collider's frame, metres.
    pub position: Vec3,
    /// World rotation of the collider's frame.
    pub rotation: Quat,
    /// The collision groups it belongs to, one bit each (default [`DEFAULT_GROUPS`]). A
    /// query sees it when `groups & mask != 0`, with the query's mask (the controller's
    /// `collide_with`).
    pub groups: u32,
}

/// The groups a collider belongs to unless told otherwise: group 0.
pub const DEFAULT_GROUPS: u32 = 1;

impl LevelCollider {
    /// A collider at `position` with no rotation.
    pub fn new(name: impl Into<String>, shape: LevelShape, position: Vec3) -> Self {
        Self {
            name: name.into(),
            shape,
            position,
            rotation: Quat::IDENTITY,
            groups: DEFAULT_GROUPS,
        }
    }

    /// The same collider in the collision groups `groups` (one bit each).
    pub fn with_groups(mut self, groups: u32) -> Self {
        self.groups = groups;
        self
    }

    /// The same collider turned by `rotation` about its frame's origin.
    pub fn rotated(mut self, rotation: Quat) -> Self {
        self.rotation = rotation;
        self
    }
}

/// A shape-cast hit against the level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelHit {
    /// Id of the collider hit (its index in the list given to [`Level::new`], or what
    /// [`Level::add`] returned).
    pub collider: usize,
    /// Fraction of the cast translation travelled before contact, in `[0, 1]`.
    pub fraction: f32,
    /// Contact point on the collider, world space.
    pub point: Vec3,
    /// Unit normal of the contact, world space, pointing from the collider towards the
    /// cast shape.
    pub normal: Vec3,
}

/// A ray hit against the level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit {
    /// Index of the collider hit.
    pub collider: usize,
    /// Distance along the (unit) ray direction, metres.
    pub distance: f32,
    /// Surface normal at the hit, world space, facing the ray's origin side.
    pub normal: Vec3,
}

/// How far a capsule is from one level primitive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelContact {
    /// Index of the collider.
    pub collider: usize,
    /// Signed distance, metres (negative: penetration depth).
    pub distance: f32,
    /// Unit direction from the collider towards the capsule (the way out), world space.
    pub normal: Vec3,
    /// The closest point on the collider, world space.
    pub point: Vec3,
}

/// A level: colliders split into primitives in a bounding-volume hierarchy (parry's BVH).
/// Colliders are known by id: their index in the list given to [`Level::new`], then what
/// [`Level::add`] returns; an id is never reused after [`Level::remove`]. A clone is a
/// deep copy (e.g. `Arc::make_mut` on a level the controller and a character share).
#[derive(Clone)]
pub struct Level {
    /// By collider id; `None` once removed.
    slots: Vec<Option<Slot>>,
    live: usize,
    /// By primitive (BVH leaf); a removed collider's slots are reused.
    prims: Vec<Prim>,
    /// The collider id of each primitive.
    owner: Vec<u32>,
    /// The collision groups of each primitive's collider.
    groups: Vec<u32>,
    free: Vec<u32>,
    bvh: Bvh,
    /// Colliders moved since [`Level::start_frame`].
    moved: Vec<u32>,
}

/// One collider of the level, with its primitives and this frame's motion.
#[derive(Clone)]
struct Slot {
    collider: LevelCollider,
    prims: Vec<u32>,
    /// Where it was at [`Level::start_frame`], when it moved since.
    from: Option<(Vec3, Quat)>,
}

impl std::fmt::Debug for Level {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Level")
            .field("colliders", &self.live)
            .field("primitives", &(self.prims.len() - self.free.len()))
            .finish()
    }
}

/// A convex polyhedron from its faces (each a convex polygon wound counter-clockwise seen
/// from outside).
fn convex(faces: &[&[Vec3]]) -> Prim {
    let mut planes = Vec::new();
    let mut triangles = Vec::new();
    for f in faces {
        let n = (f[1] - f[0]).cross(f[2] - f[0]).normalize();
        planes.push((n, n.dot(f[0])));
        for k in 1..f.len() - 1 {
            triangles.push([f[0], f[k], f[k + 1]]);
        }
    }
    let normals = triangles
        .iter()
        .map(|t: &[Vec3; 3]| (t[1] - t[0]).cross(t[2] - t[0]).normalize_or_zero())
        .collect();
    Prim::Convex {
        planes,
        triangles,
        normals,
    }
}

pub(super) fn build_prims(c: &LevelCollider, out: &mut Vec<Prim>) -> Result<()> {
    let bad = |what: String| {
        Err(Error::InvalidParameter(format!(
            "level collider '{}': {what}",
            c.name
        )))
    };
    let positive = |x: f32| x.is_finite() && x > 0.0;
    let rot = c.rotation.normalize();
    let world = |p: Vec3| c.position + rot * p;
    match &c.shape {
        LevelShape::Box { half_extents: h } => {
            if !(positive(h.x) && positive(h.y) && positive(h.z)) {
                return bad(format!("box half extents {h} must be finite and > 0"));
            }
            out.push(Prim::Cuboid {
                centre: c.position,
                rotation: rot,
                half: *h,
            });
        }
        LevelShape::Sphere { radius } => {
            if !positive(*radius) {
                return bad(format!("sphere radius {radius} must be finite and > 0"));
            }
            out.push(Prim::Sphere {
                centre: c.position,
                radius: *radius,
            });
        }
        LevelShape::Capsule {
            half_height,
            radius,
        } => {
            if !(positive(*radius) && half_height.is_finite() && *half_height >= 0.0) {
                return bad(format!(
                    "capsule radius {radius} must be > 0 and half height {half_height} ≥ 0"
                ));
            }
            out.push(Prim::Capsule {
                a: world(Vec3::new(0.0, -half_height, 0.0)),
                b: world(Vec3::new(0.0, *half_height, 0.0)),
                radius: *radius,
            });
        }
        LevelShape::Ramp {
            width,
            length,
            height,
        } => {
            if !(positive(*width) && positive(*length) && positive(*height)) {
                return bad(format!(
                    "ramp width {width}, length {length} and height {height} must be finite and > 0"
                ));
            }
            let (w, l, h) = (0.5 * width, *length, *height);
            let p = [
                Vec3::new(-w, 0.0, 0.0),
                Vec3::new(w, 0.0, 0.0),
                Vec3::new(-w, 0.0, l),
                Vec3::new(w, 0.0, l),
                Vec3::new(-w, h, l),
                Vec3::new(w, h, l),
            ]
            .map(world);
            out.push(convex(&[
                &[p[0], p[1], p[3], p[2]],
                &[p[2], p[3], p[5], p[4]],
                &[p[0], p[4], p[5], p[1]],
                &[p[0], p[2], p[4]],
                &[p[1], p[5], p[3]],
            ]));
        }
        LevelShape::TriMesh { vertices, indices } => {
            if indices.is_empty() {
                return bad("triangle mesh has no triangles".into());
            }
            if let Some(v) = vertices.iter().find(|v| !v.is_finite()) {
                return bad(format!("triangle mesh vertex {v} is not finite"));
            }
            let before = out.len();
            for (t, tri) in indices.iter().enumerate() {
                if let Some(&i) = tri.iter().find(|&&i| i as usize >= vertices.len()) {
                    return bad(format!(
                        "triangle {t} names vertex {i}, but the mesh has {} vertices",
                        vertices.len()
                    ));
                }
                let v = tri.map(|i| world(vertices[i as usize]));
                let n = (v[1] - v[0]).cross(v[2] - v[0]);
                if n.length() > 1e-12 {
                    out.push(Prim::Triangle {
                        v,
                        normal: n.normalize(),
                    });
                }
            }
            if out.len() == before {
                return bad("every triangle of the mesh is degenerate".into());
            }
        }
    }
    Ok(())
}

/// The capsule's segment: `half_height` along the local Y of `rotation` about `centre`.
pub(crate) fn segment(centre: Vec3, rotation: Quat, half_height: f32) -> (Vec3, Vec3) {
    let axis = rotation * Vec3::Y * half_height;
    (centre - axis, centre + axis)
}

/// The checks every collider passes before it enters a level.
fn check_placement(c: &LevelCollider) -> Result<()> {
    if !c.position.is_finite() || !c.rotation.is_finite() || c.rotation.length() < 1e-6 {
        return Err(Error::InvalidParameter(format!(
            "level collider '{}': position {} / rotation {} must be finite (rotation non-zero)",
            c.name, c.position, c.rotation
        )));
    }
    Ok(())
}

/// A primitive's BVH leaf box.
fn leaf(p: &Prim) -> Aabb {
    let (lo, hi) = p.bounds();
    Aabb::new(lo, hi).loosened(1e-4)
}

/// The most primitives a level holds (BVH leaf indices are `u32`).
const MAX_PRIMS: usize = u32::MAX as usize / 2;

impl Level {
    /// Builds a level from `colliders` (their ids are their indices). Errors name the
    /// collider and the problem (non-finite placement, a non-positive size, a triangle
    /// naming a missing vertex).
    pub fn new(colliders: Vec<LevelCollider>) -> Result<Self> {
        let mut prims = Vec::new();
        let mut owner = Vec::new();
        let mut groups = Vec::new();
        let mut slots = Vec::with_capacity(colliders.len());
        for (i, c) in colliders.into_iter().enumerate() {
            check_placement(&c)?;
            let first = prims.len();
            build_prims(&c, &mut prims)?;
            if prims.len() > MAX_PRIMS {
                return Err(Error::InvalidParameter(format!(
                    "level has {} primitives; too many",
                    prims.len()
                )));
            }
            owner.resize(prims.len(), i as u32);
            groups.resize(prims.len(), c.groups);
            slots.push(Some(Slot {
                collider: c,
                prims: (first as u32..prims.len() as u32).collect(),
                from: None,
            }));
        }
        let leaves: Vec<Aabb> = prims.iter().map(leaf).collect();
        let bvh = Bvh::from_leaves(BvhBuildStrategy::Binned, &leaves);
        Ok(Self {
            live: slots.len(),
            slots,
            prims,
            owner,
            groups,
            free: Vec::new(),
            bvh,
            moved: Vec::new(),
        })
    }

    /// Number of colliders in the level.
    pub fn len(&self) -> usize {
        self.live
    }

    /// True without colliders.
    pub fn is_empty(&self) -> bool {
        self.live == 0
    }

    /// Number of primitives (a triangle mesh counts its triangles).
    pub fn primitive_count(&self) -> usize {
        self.prims.len() - self.free.len()
    }

    /// The colliders in the level with their ids, in id order.
    pub fn colliders(&self) -> impl Iterator<Item = (usize, &LevelCollider)> + '_ {
        self.slots
            .iter()
            .enumerate()
            .filter_map(|(i, s)| s.as_ref().map(|s| (i, &s.collider)))
    }

    /// Collider `id`, as it is now; `None` if there is none (never was, or removed).
    pub fn collider(&self, id: usize) -> Option<&LevelCollider> {
        self.slot(id).map(|s| &s.collider)
    }

    fn slot(&self, id: usize) -> Option<&Slot> {
        self.slots.get(id).and_then(Option::as_ref)
    }

    /// World-space bounds of collider `id` (min, max); `None` if there is no such collider.
    pub fn bounds(&self, id: usize) -> Option<(Vec3, Vec3)> {
        let slot = self.slot(id)?;
        slot.prims
            .iter()
            .map(|&k| self.prims[k as usize].bounds())
            .reduce(|(a, b), (lo, hi)| (a.min(lo), b.max(hi)))
    }

    /// Sweeps the capsule `a`–`b` of `radius` along `translation` and returns the first
    /// contact before its end. Contacts the motion leaves or slides along are ignored, so
    /// a capsule resting on a floor walks on it. Ties go to the lower primitive. Only
    /// colliders whose groups meet `mask` count.
    pub(crate) fn cast(
        &self,
        a: Vec3,
        b: Vec3,
        radius: f32,
        translation: Vec3,
        mask: u32,
    ) -> Option<LevelHit> {
        let (lo, hi) = (a.min(b) - radius, a.max(b) + radius);
        let swept = Aabb::new(lo.min(lo + translation), hi.max(hi + translation)).loosened(1e-3);
        let mut best: Option<(f32, u32, Separation)> = None;
        for leaf in self.bvh.intersect_aabb(&swept) {
            if self.groups[leaf as usize] & mask == 0 {
                continue;
            }
            let Some((t, s)) = self.prims[leaf as usize].sweep(a, b, radius, translation) else {
                continue;
            };
            let better = match &best {
                None => true,
                Some((bt, bl, _)) => t < *bt || (t == *bt && leaf < *bl),
            };
            if better {
                best = Some((t, leaf, s));
            }
        }
        best.map(|(t, leaf, s)| LevelHit {
            collider: self.owner[leaf as usize] as usize,
            fraction: t.clamp(0.0, 1.0),
            point: s.point,
            normal: s.normal,
        })
    }

    /// Sweeps a capsule (`radius`, `half_height` along the local Y of `rotation`, centred
    /// at `position`) along `translation`: the first contact, if any, before its end.
    pub fn sweep_capsule(
        &self,
        radius: f32,
        half_height: f32,
        position: Vec3,
        rotation: Quat,
        translation: Vec3,
    ) -> Option<LevelHit> {
        let finite = radius.is_finite()
            && half_height.is_finite()
            && position.is_finite()
            && rotation.is_finite()
            && translation.is_finite();
        if !finite || rotation.length() < 1e-6 {
            return None;
        }
        let (a, b) = segment(position, rotation.normalize(), half_height.max(0.0));
        self.cast(a, b, radius.max(0.0), translation, u32::MAX)
    }

    /// Casts a ray from `origin` along unit `dir` up to `max_distance` metres: the first
    /// surface it reaches from outside. A ray that starts inside a solid reports nothing
    /// for that solid.
    pub fn ray(&self, origin: Vec3, dir: Vec3, max_distance: f32) -> Option<RayHit> {
        self.ray_masked(origin, dir, max_distance, u32::MAX)
    }

    /// [`Level::ray`] seeing only the colliders whose groups meet `mask`.
    pub fn ray_masked(
        &self,
        origin: Vec3,
        dir: Vec3,
        max_distance: f32,
        mask: u32,
    ) -> Option<RayHit> {
        if !(origin.is_finite() && dir.is_finite() && max_distance.is_finite()) {
            return None;
        }
        let dir = dir.normalize_or_zero();
        if dir == Vec3::ZERO || max_distance <= 0.0 {
            return None;
        }
        let v = dir * max_distance;
        let bounds = Aabb::new(origin.min(origin + v), origin.max(origin + v)).loosened(1e-3);
        let mut best: Option<(f32, u32, Vec3)> = None;
        for leaf in self.bvh.intersect_aabb(&bounds) {
            if self.groups[leaf as usize] & mask == 0 {
                continue;
            }
            let p = &self.prims[leaf as usize];
            if p.sdf(origin).0 < 0.0 {
                continue;
            }
            let Some((t, s)) = p.sweep(origin, origin, 0.0, v) else {
                continue;
            };
            if best.is_none_or(|(bt, bl, _)| t < bt || (t == bt && leaf < bl)) {
                best = Some((t, leaf, s.normal));
            }
        }
        best.map(|(t, leaf, normal)| RayHit {
            collider: self.owner[leaf as usize] as usize,
            distance: t * max_distance,
            normal,
        })
    }

    /// Every primitive closer to the capsule `a`–`b` of `radius` than `within` metres
    /// (negative distances are penetrations), by collider and distance; only colliders
    /// whose groups meet `mask`.
    pub(crate) fn contacts(
        &self,
        a: Vec3,
        b: Vec3,
        radius: f32,
        within: f32,
        mask: u32,
        out: &mut Vec<LevelContact>,
    ) {
        out.clear();
        let r = radius + within.max(0.0);
        let bounds = Aabb::new(a.min(b) - r, a.max(b) + r);
        for leaf in self.bvh.intersect_aabb(&bounds) {
            if self.groups[leaf as usize] & mask == 0 {
                continue;
            }
            let s = self.prims[leaf as usize].separation(a, b, radius);
            if s.distance < within {
                out.push(LevelContact {
                    collider: self.owner[leaf as usize] as usize,
                    distance: s.distance,
                    normal: s.normal,
                    point: s.point,
                });
            }
        }
        out.sort_by(|x, y| {
            x.collider
                .cmp(&y.collider)
                .then(x.distance.total_cmp(&y.distance))
        });
    }

    /// Whether any level primitive's bounds overlap the box `lo`–`hi` (a broad-phase
    /// test: one BVH query).
    pub(crate) fn touches_aabb(&self, lo: Vec3, hi: Vec3) -> bool {
        if !(lo.is_finite() && hi.is_finite()) {
            return false;
        }
        self.bvh.intersect_aabb(&Aabb::new(lo, hi)).next().is_some()
    }

    /// The deepest penetration of a sphere of radius `r` at `p` into the level: its
    /// depth and the way out; `None` when it touches nothing. Allocates nothing.
    pub(crate) fn deepest_contact(&self, p: Vec3, r: f32) -> Option<(f32, Vec3)> {
        let bounds = Aabb::new(p - r, p + r);
        let mut best: Option<(f32, Vec3)> = None;
        for leaf in self.bvh.intersect_aabb(&bounds) {
            let s = self.prims[leaf as usize].separation(p, p, r);
            if s.distance < 0.0 && best.is_none_or(|(d, _)| -s.distance > d) {
                best = Some((-s.distance, s.normal));
            }
        }
        best
    }

    /// The deepest penetration of a capsule (`radius`, `half_height` along the local Y of
    /// `rotation`, centred at `position`) into the level, metres; 0 when it is free.
    pub fn capsule_penetration(
        &self,
        radius: f32,
        half_height: f32,
        position: Vec3,
        rotation: Quat,
    ) -> f32 {
        let (a, b) = segment(position, rotation, half_height);
        let mut out = Vec::new();
        self.contacts(a, b, radius, 0.0, u32::MAX, &mut out);
        out.iter().map(|p| -p.distance).fold(0.0, f32::max)
    }
}
