//! One character's bone cloth with its contact tests and its angle limit in SIMD lanes:
//! the cloth job's `collide` (points, structural segments and quad triangles against the
//! cloth's colliders) and `limit_angles` (the chains side by side, one per lane), giving
//! the scalar functions' bits.
//!
//! - **Points**: a point's answer depends on that point alone, so [`LANES`] points go side
//!   by side through every collider in order: the collider's quick rejection and, for
//!   keep-out spheres and capsules, the narrow phase's contact decision and push out
//!   (`collide/lanes.rs`, the chain lanes' too); a step that *entered* a shape, and every
//!   other shape, goes to the scalar collider for the lanes that need it.
//! - **Segments and triangles** are tested in order, and a push moves points that later
//!   segments and triangles share, so the lanes *look ahead*: before the pass they test
//!   every segment's quick rejection, and every triangle's whole contact decision (its
//!   frame, the cheap reject, the closest points by alternating projections, the side
//!   memory), from the points as they are. Then the pass walks in the scalar order: a
//!   segment or triangle none of whose points an earlier push in the pass moved takes the
//!   lanes' answer (the same bits: the same operations on the same inputs); one that
//!   would be pushed, or whose points moved, is done by the scalar code from there on.
//!   Where nothing touches (most of the time), nothing is left to the scalar code.

use crate::collide::lanes::{capsule_contact, sphere_contact};
use crate::collide::{PlacedCollider, Shape};
use crate::dynamics::cloth::compile::ClothRig;
use crate::dynamics::cloth::contact::{
    push_segment, push_triangle_against, push_triangle_against_from, Core, TriangleFrame,
};
use crate::dynamics::cloth::SurfaceCollision;
use crate::lanes::{
    angle_between, closest_point_on_segment, differs, rotation_arc, turned_toward, Lane, Mask, F,
    LANES, M, V3,
};
use crate::lanes::{vmax, vmin};
use crate::math::same_bits;
use glam::Vec3;

#[cfg(target_arch = "x86_64")]
use crate::lanes::avx::Fa;
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx512::Fz;
use crate::lanes::Isa;

/// What one contact pass keeps between its look-ahead and its walk. Lives in the cloth
/// state; sized on first use, so a frame allocates nothing.
#[derive(Debug, Clone, Default)]
pub(crate) struct ClothLaneScratch {
    /// The cloth's colliders as the point pass sees them.
    shapes: Vec<PointShape>,
    /// Per point: moved by a push earlier in this pass.
    dirty: Vec<bool>,
    /// Per structural segment: bit `j` set when core slot `j` rejects it.
    far: Vec<u64>,
    /// Per triangle: its frame (`None`: degenerate).
    frames: Vec<Option<TriangleFrame>>,
    /// Per triangle and core slot: the side memory after the pair's test where it pushes
    /// nothing (±1), or 0 where the scalar code must do it (it pushes, or no answer).
    sides: Vec<i8>,
}

/// The cloth job's `collide`, computed with lanes in the lane type `isa` chose. The same arguments and results, bit for bit.
#[allow(clippy::too_many_arguments)]
pub(crate) fn collide(
    isa: Isa,
    rig: &ClothRig,
    ci: usize,
    colliders: &[PlacedCollider],
    pos: &mut [Vec3],
    prev: Option<&[Vec3]>,
    contact: Option<(&mut [f32], &mut [i8])>,
    surfaces: bool,
    cores: &mut Vec<Option<Core>>,
    scratch: &mut ClothLaneScratch,
) -> bool {
    let mut pass = Pass {
        rig,
        ci,
        colliders,
        pos,
        prev,
        contact,
        surfaces,
        cores,
        scratch,
    };
    // SAFETY (both): the function only requires the instructions of its lane type, and
    // `Isa::of` chose that type because the CPU has them.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    match isa {
        Isa::Avx512 => return unsafe { pass.run_avx512() },
        Isa::Avx2 => return unsafe { pass.run_avx2() },
        Isa::Portable => {}
    }
    let _ = isa;
    pass.run::<F>()
}

/// The cloth job's `limit_angles`, one chain per lane, [`LANES`] chains side by side
/// going down their points together, in the lane type `isa` chose. The lanes compute each segment's angle to its expected
/// direction and, for a segment past the limit, its turn back (the scalar operations, so
/// the same bits). A chain's points are its own, so chains side by side give what one
/// after another gives.
pub(crate) fn limit_angles(
    isa: Isa,
    rig: &ClothRig,
    ci: usize,
    targets: &[Vec3],
    pos: &mut [Vec3],
) {
    // SAFETY (both): the function only requires the instructions of its lane type, and
    // `Isa::of` chose that type because the CPU has them.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    match isa {
        Isa::Avx512 => return unsafe { limit_angles_avx512(rig, ci, targets, pos) },
        Isa::Avx2 => return unsafe { limit_angles_avx2(rig, ci, targets, pos) },
        Isa::Portable => {}
    }
    let _ = isa;
    limit_angles_in::<F>(rig, ci, targets, pos)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn limit_angles_avx2(rig: &ClothRig, ci: usize, targets: &[Vec3], pos: &mut [Vec3]) {
    limit_angles_in::<Fa>(rig, ci, targets, pos)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
fn limit_angles_avx512(rig: &ClothRig, ci: usize, targets: &[Vec3], pos: &mut [Vec3]) {
    limit_angles_in::<Fz>(rig, ci, targets, pos)
}

#[inline(always)]
fn limit_angles_in<T: Lane>(rig: &ClothRig, ci: usize, targets: &[Vec3], pos: &mut [Vec3]) {
    let cloth = &rig.cloths[ci];
    let limit = cloth.settings.limit_angle.to_radians();
    for group in cloth.chains.chunks(LANES) {
        // Point `k` of each chain of the group (lanes past a chain's end left at zero).
        // (In `F`: the conversion to `T` is left to the caller, a closure being compiled
        // without its caller's target features: see `collide::lanes::select_max`.)
        let gather = |k: usize, from: &[Vec3]| {
            let mut v = V3::ZERO;
            for (l, ch) in group.iter().enumerate() {
                if ch.start + k < ch.end {
                    v.set(l, from[ch.start + k]);
                }
            }
            v
        };
        let longest = group.iter().map(|ch| ch.len()).max().unwrap_or(0);
        let (mut t_parent, mut p_parent) =
            (V3::<T>::of(gather(0, targets)), V3::<T>::of(gather(0, pos)));
        let (mut t_grand, mut p_grand) = (t_parent, p_parent);
        for k in 1..longest {
            let (t, mut p) = (V3::<T>::of(gather(k, targets)), V3::<T>::of(gather(k, pos)));
            let anim = t - t_parent;
            let expected = if k > 1 {
                rotation_arc(t_parent - t_grand, p_parent - p_grand).mul_vec3(anim)
            } else {
                anim
            };
            let sim = p - p_parent;
            // NaN is not past the limit.
            let over = angle_between(expected, sim).gt(T::splat(limit));
            // Lanes of free points of the group's chains.
            let mut free = M::NONE;
            for (l, ch) in group.iter().enumerate() {
                let i = ch.start + k;
                if i < ch.end && !rig.fixed[i] {
                    free.0[l] = !0;
                }
            }
            let over = over.and(<T::M as Mask>::of(free));
            if over.any() {
                // The scalar `limit_angles`' turn back onto the cone.
                let unit = expected.normalize_or(V3::splat(Vec3::NEG_Y));
                let dir = turned_toward(expected, sim, unit, limit);
                p = V3::select(over, p_parent + dir * sim.length(), p);
                let (over, pf) = (over.m(), p.f());
                for (l, ch) in group.iter().enumerate() {
                    if over.0[l] != 0 {
                        pos[ch.start + k] = pf.get(l);
                    }
                }
            }
            (t_grand, t_parent) = (t_parent, t);
            (p_grand, p_parent) = (p_parent, p);
        }
    }
}

/// A collider as the point pass asks it: where it is, its bounding radius (`None`: it
/// acts everywhere), and for keep-out spheres and capsules the radius whose contact the
/// lanes decide (a capsule with its axis ends).
#[derive(Debug, Clone, Copy)]
struct PointShape {
    index: usize,
    centre: Vec3,
    bound: Option<f32>,
    radius: Option<f32>,
    ends: Option<(Vec3, Vec3)>,
}

impl PointShape {
    fn of_at(index: usize, col: &PlacedCollider) -> PointShape {
        let (radius, ends) = match col.shape {
            Shape::Sphere {
                radius,
                inside: false,
            } => (Some(radius), None),
            Shape::Capsule { radius, length } => (Some(radius), Some(col.capsule_ends(length))),
            _ => (None, None),
        };
        PointShape {
            index,
            centre: col.transform.translation,
            bound: col.bounding_radius(),
            radius,
            ends,
        }
    }
}

/// One `collide` call's inputs.
struct Pass<'a> {
    rig: &'a ClothRig,
    ci: usize,
    colliders: &'a [PlacedCollider],
    pos: &'a mut [Vec3],
    prev: Option<&'a [Vec3]>,
    contact: Option<(&'a mut [f32], &'a mut [i8])>,
    surfaces: bool,
    cores: &'a mut Vec<Option<Core>>,
    scratch: &'a mut ClothLaneScratch,
}

impl Pass<'_> {
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn run_avx2(&mut self) -> bool {
        // The explicit AVX2 lane type, only here after the CPU was found to have AVX2.
        self.run::<Fa>()
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    fn run_avx512(&mut self) -> bool {
        // The explicit AVX-512 lane type, only here after the CPU was found to have it.
        self.run::<Fz>()
    }

    /// The scalar `collide`'s passes in its order: points, segments, triangles.
    #[inline(always)]
    fn run<T: Lane>(&mut self) -> bool {
        let (rig, colliders) = (self.rig, self.colliders);
        let cloth = &rig.cloths[self.ci];
        let mut touched = self.points::<T>();
        self.cores.clear();
        self.cores
            .extend(cloth.colliders.iter().map(|&k| Core::of(&colliders[k])));
        let n = rig.point_count();
        self.scratch.dirty.resize(n, false);
        if cloth.settings.segment_collision {
            touched |= self.segments::<T>();
        }
        let mode = cloth.settings.surface_collision;
        // With the surface test off, every triangle leaves everything as it is.
        if self.surfaces && self.contact.is_some() && mode != SurfaceCollision::Off {
            touched |= self.triangles::<T>(mode);
        }
        touched
    }

    /// Every free point against the cloth's colliders in order, as
    /// [`PlacedCollider::resolve`] one collider after another, [`LANES`] points at a time
    /// (a point's answer depends on that point alone, so taking the points of a group
    /// through every collider gives what the scalar pass, collider by collider, gives). A
    /// moved point is written back (and gets the cloth's friction with `contact`).
    /// Returns whether any moved.
    #[inline(always)]
    fn points<T: Lane>(&mut self) -> bool {
        let rig = self.rig;
        let cloth = &rig.cloths[self.ci];
        let shapes = &mut self.scratch.shapes;
        shapes.clear();
        shapes.extend(
            cloth
                .colliders
                .iter()
                .map(|&k| PointShape::of_at(k, &self.colliders[k])),
        );
        let shapes = &self.scratch.shapes;
        let points = cloth.points.clone();
        let mut touched = false;
        let mut start = points.start;
        while start < points.end {
            let n = (points.end - start).min(LANES);
            let (mut x, mut q, mut r, mut active) = (V3::ZERO, V3::ZERO, F([0.0; LANES]), M::NONE);
            for l in 0..n {
                let p = start + l;
                if rig.fixed[p] {
                    continue;
                }
                active.0[l] = !0;
                x.set(l, self.pos[p]);
                q.set(l, self.prev.map_or(self.pos[p], |pr| pr[p]));
                r.0[l] = rig.radius[p];
            }
            let (x, q, r) = (V3::<T>::of(x), V3::<T>::of(q), T::of(r));
            let active = <T::M as Mask>::of(active);
            // `y`: the point as the colliders so far left it; `moved`: lanes any changed.
            let (mut y, mut moved) = (x, <T::M as Mask>::NONE);
            for shape in shapes {
                // Without a step start, each collider takes the point as it finds it.
                let from = if self.prev.is_some() { q } else { y };
                let centre = V3::<T>::splat(shape.centre);
                let mut ask = active;
                // `resolve`'s quick rejection: both ends of the step beyond the shape's
                // bounding sphere and the step too short to reach it.
                if let Some(bound) = shape.bound {
                    let reach = T::splat(bound) + r;
                    let reach2 = reach * reach;
                    let (dp, dq, step) = (y - centre, from - centre, y - from);
                    let gap = dp.length() - reach;
                    let rejected = dp
                        .dot(dp)
                        .gt(reach2)
                        .and(dq.dot(dq).gt(reach2))
                        .and(step.dot(step).lt(gap * gap));
                    ask = ask.and(rejected.not());
                }
                if !ask.any() {
                    continue;
                }
                let mut after = y;
                if let Some(radius) = shape.radius {
                    let limit = T::splat(radius) + r;
                    let c = match shape.ends {
                        Some((a, b)) => capsule_contact(y, from, V3::splat(a), V3::splat(b), limit),
                        None => sphere_contact(y, from, centre, limit),
                    };
                    ask = ask.and(c.may);
                    after = V3::select(ask.and(c.entered.not()), c.pushed(), after);
                    ask = ask.and(c.entered);
                }
                // The scalar collider for what the lanes leave: entries, other shapes.
                if ask.any() {
                    let (ask, mut af, yf, ff) = (ask.m(), after.f(), y.f(), from.f());
                    let col = &self.colliders[shape.index];
                    for l in 0..n {
                        if ask.0[l] != 0 {
                            let p = start + l;
                            af.set(l, col.resolve(yf.get(l), ff.get(l), rig.radius[p]));
                        }
                    }
                    after = V3::of(af);
                }
                // Taken where it differs by value, as the scalar `after != before`.
                let changed = differs(after, y).and(active);
                y = V3::select(changed, after, y);
                moved = moved.or(changed);
            }
            if moved.any() {
                let (moved, yf) = (moved.m(), y.f());
                for l in 0..n {
                    if moved.0[l] != 0 {
                        let p = start + l;
                        self.pos[p] = yf.get(l);
                        touched = true;
                        if let Some((friction, _)) = self.contact.as_mut() {
                            friction[p] = rig.friction[p];
                        }
                    }
                }
            }
            start += n;
        }
        touched
    }

    /// The structural segments against the cores, in order (as the scalar pass), with
    /// the quick rejections looked ahead in lanes.
    #[inline(always)]
    fn segments<T: Lane>(&mut self) -> bool {
        let rig = self.rig;
        let cloth = &rig.cloths[self.ci];
        let cores = &self.cores[..];
        let scratch = &mut *self.scratch;
        scratch.far.clear();
        for chunk in cloth.structural.chunks(LANES) {
            let (mut a, mut b, mut r) = (V3::ZERO, V3::ZERO, F([0.0; LANES]));
            for (l, &c) in chunk.iter().enumerate() {
                let c = &rig.constraints[c as usize];
                let (i, j) = (c.a as usize, c.b as usize);
                a.set(l, self.pos[i]);
                b.set(l, self.pos[j]);
                r.0[l] = 0.5 * (rig.radius[i] + rig.radius[j]);
            }
            let (a, b, r) = (V3::<T>::of(a), V3::<T>::of(b), T::of(r));
            let (lo, hi) = (vmin(a, b), vmax(a, b));
            let mut far = [0u64; LANES];
            for (slot, core) in cores.iter().enumerate().take(64) {
                let Some(core) = core else { continue };
                let reach = T::splat(core.radius) + r + T::splat(1e-4);
                let gap = vmax(lo - V3::splat(core.hi), V3::splat(core.lo) - hi);
                let is_far = max_element(gap).gt(reach).m();
                for (l, f) in far.iter_mut().enumerate() {
                    *f |= u64::from(is_far.0[l] != 0) << slot;
                }
            }
            scratch.far.extend_from_slice(&far[..chunk.len()]);
        }
        // The core slots the lanes answer for: a segment all of them reject is done.
        let all = cores
            .iter()
            .take(64)
            .enumerate()
            .filter(|(_, c)| c.is_some())
            .fold(0u64, |bits, (slot, _)| bits | 1 << slot);
        let every_slot_answered = cores.len() <= 64;
        let points = cloth.points.clone();
        scratch.dirty[points].iter_mut().for_each(|d| *d = false);
        let mut touched = false;
        for (i, &c) in cloth.structural.iter().enumerate() {
            let c = &rig.constraints[c as usize];
            let (a, b) = (c.a as usize, c.b as usize);
            // The lanes' rejections hold while neither end has moved in this pass.
            let far = if scratch.dirty[a] || scratch.dirty[b] {
                0
            } else {
                scratch.far[i]
            };
            if every_slot_answered && far == all {
                continue;
            }
            let r = 0.5 * (rig.radius[a] + rig.radius[b]);
            let (lo, hi) = (self.pos[a].min(self.pos[b]), self.pos[a].max(self.pos[b]));
            for (slot, core) in cores.iter().enumerate() {
                let Some(core) = core else { continue };
                if slot < 64 && far & (1 << slot) != 0 {
                    continue;
                }
                // The scalar pass's own quick rejection and push.
                let reach = core.radius + r + 1e-4;
                let gap = (lo - core.hi).max(core.lo - hi);
                if gap.max_element() > reach {
                    continue;
                }
                let (mut pa, mut pb) = (self.pos[a], self.pos[b]);
                if push_segment(
                    &mut pa,
                    &mut pb,
                    [!rig.fixed[a], !rig.fixed[b]],
                    (core.e0, core.e1, core.radius + r),
                ) {
                    self.pos[a] = pa;
                    self.pos[b] = pb;
                    scratch.dirty[a] = true;
                    scratch.dirty[b] = true;
                    touched = true;
                }
            }
        }
        touched
    }

    /// The quads' triangles against the cores, in order (as the scalar pass), with each
    /// pair's whole decision looked ahead in lanes.
    #[inline(always)]
    fn triangles<T: Lane>(&mut self, mode: SurfaceCollision) -> bool {
        let rig = self.rig;
        let cloth = &rig.cloths[self.ci];
        let cores = &self.cores[..];
        let m = cores.len();
        let Some((_, sides)) = self.contact.as_mut() else {
            return false;
        };
        let scratch = &mut *self.scratch;
        let tris = &cloth.triangles;
        scratch.frames.clear();
        scratch.sides.clear();
        scratch.sides.resize(tris.len() * m, 0);
        let push_pull = mode == SurfaceCollision::PushPull;
        // A close pair whose projections wait for a second one to run beside.
        let mut waiting: Option<ClosePair<T>> = None;
        for (g, chunk) in tris.chunks(LANES).enumerate() {
            let (mut p0, mut p1, mut p2) = (V3::ZERO, V3::ZERO, V3::ZERO);
            let mut r = F([0.0; LANES]);
            for (l, &[i0, i1, i2]) in chunk.iter().enumerate() {
                let [i0, i1, i2] = [i0, i1, i2].map(|i| i as usize);
                p0.set(l, self.pos[i0]);
                p1.set(l, self.pos[i1]);
                p2.set(l, self.pos[i2]);
                r.0[l] = rig.radius[i0] + rig.radius[i1] + rig.radius[i2];
            }
            let (p0, p1, p2) = (V3::<T>::of(p0), V3::<T>::of(p1), V3::<T>::of(p2));
            let r = T::of(r) / T::splat(3.0);
            // `TriangleFrame::of`.
            let raw = (p1 - p0).cross(p2 - p0);
            let raw2 = raw.dot(raw);
            let valid = raw2.lt(T::splat(1e-14)).not();
            let normal = raw * (T::splat(1.0) / raw2.sqrt());
            let centroid = (p0 + p1 + p2) / T::splat(3.0);
            let (d0, d1, d2) = (p0 - centroid, p1 - centroid, p2 - centroid);
            let bound = d0.dot(d0).max(d1.dot(d1)).max(d2.dot(d2)).sqrt();
            let (validm, nf, cf, bf) = (valid.m(), normal.f(), centroid.f(), bound.f());
            for l in 0..chunk.len() {
                scratch
                    .frames
                    .push((validm.0[l] != 0).then(|| TriangleFrame {
                        normal: nf.get(l),
                        centroid: cf.get(l),
                        bound: bf.0[l],
                    }));
            }
            let zero = T::splat(0.0);
            let (one, minus_one) = (T::splat(1.0), T::splat(-1.0));
            for (slot, core) in cores.iter().enumerate() {
                let Some(core) = core else { continue };
                let (e0, e1) = (V3::<T>::splat(core.e0), V3::<T>::splat(core.e1));
                let radius = T::splat(core.radius) + r;
                // The cheap reject (the side memory still learns where the collider is).
                let near = closest_point_on_segment(centroid, e0, e1);
                let far = (near - centroid).length().gt(bound + radius);
                let side_far = T::select(zero.le(normal.dot(near - p0)), one, minus_one);
                let close = far.not().and(valid);
                if !close.any() {
                    let side = side_far.f();
                    let at = g * LANES * m + slot;
                    for l in 0..chunk.len() {
                        scratch.sides[at + l * m] = if side.0[l] > 0.0 { 1 } else { -1 };
                    }
                    continue;
                }
                let pair = ClosePair {
                    at: g * LANES * m + slot,
                    len: chunk.len(),
                    corners: [p0, p1, p2],
                    normal,
                    ends: (e0, e1),
                    radius,
                    close,
                    side_far,
                    c: near,
                    q: closest_point_on_triangle(near, p0, p1, p2),
                    // A sphere's core is a point: its closest point is already found.
                    going: if core.e0 != core.e1 {
                        close
                    } else {
                        <T::M as Mask>::NONE
                    },
                };
                // Two pairs' alternating projections side by side: each round waits on
                // the one before, so a second, independent chain keeps the processor
                // busy meanwhile (the same operations per pair, so the same bits).
                match waiting.take() {
                    None => waiting = Some(pair),
                    Some(mut first) => {
                        let mut second = pair;
                        project_together(&mut first, Some(&mut second));
                        first.decide(sides, &mut scratch.sides, m, push_pull);
                        second.decide(sides, &mut scratch.sides, m, push_pull);
                    }
                }
            }
        }
        if let Some(mut last) = waiting.take() {
            project_together(&mut last, None);
            last.decide(sides, &mut scratch.sides, m, push_pull);
        }
        let points = cloth.points.clone();
        scratch.dirty[points].iter_mut().for_each(|d| *d = false);
        let mut touched = false;
        for (t, &[i0, i1, i2]) in tris.iter().enumerate() {
            let [i0, i1, i2] = [i0, i1, i2].map(|i| i as usize);
            let free = [!rig.fixed[i0], !rig.fixed[i1], !rig.fixed[i2]];
            if !free.iter().any(|f| *f) {
                // Every collider leaves a triangle without a free corner alone.
                continue;
            }
            let sides = &mut sides[t * m..(t + 1) * m];
            let r = || (rig.radius[i0] + rig.radius[i1] + rig.radius[i2]) / 3.0;
            let corners = [self.pos[i0], self.pos[i1], self.pos[i2]];
            let (after, moved) = if scratch.dirty[i0] || scratch.dirty[i1] || scratch.dirty[i2] {
                push_triangle_against(corners, free, r(), cores, mode, sides)
            } else {
                // A degenerate triangle is left alone by every collider.
                let Some(frame) = scratch.frames[t] else {
                    continue;
                };
                // The lanes' answers up to the first pair that pushes.
                let answers = &scratch.sides[t * m..(t + 1) * m];
                let mut pushes = None;
                for slot in 0..m {
                    if cores[slot].is_none() {
                        continue;
                    }
                    match answers[slot] {
                        0 => {
                            pushes = Some(slot);
                            break;
                        }
                        side => sides[slot] = side,
                    }
                }
                // None pushes: the corners stay as they are.
                let Some(slot) = pushes else { continue };
                push_triangle_against_from(
                    corners,
                    Some(frame),
                    free,
                    r(),
                    &cores[slot..],
                    mode,
                    &mut sides[slot..],
                )
            };
            touched |= moved;
            for (corner, i) in after.into_iter().zip([i0, i1, i2]) {
                if !same_bits(corner, self.pos[i]) {
                    scratch.dirty[i] = true;
                }
                self.pos[i] = corner;
            }
        }
        touched
    }
}

/// A triangle group and a core slot with some triangle near the core: what its
/// alternating projections and decision need.
struct ClosePair<T: Lane> {
    /// Where the group's first triangle's slot is in the look-ahead's side array.
    at: usize,
    /// Triangles in the group.
    len: usize,
    corners: [V3<T>; 3],
    normal: V3<T>,
    ends: (V3<T>, V3<T>),
    radius: T,
    /// Lanes past the cheap reject (and not degenerate).
    close: T::M,
    /// The side memory the cheap reject learns.
    side_far: T,
    /// The closest points so far: on the core, on the triangle.
    c: V3<T>,
    q: V3<T>,
    /// Lanes whose projections have not reached their fixed point.
    going: T::M,
}

impl<T: Lane> ClosePair<T> {
    /// One round of the alternating projections, in the lanes still going.
    #[inline(always)]
    fn project(&mut self) {
        let [p0, p1, p2] = self.corners;
        let next = closest_point_on_segment(self.q, self.ends.0, self.ends.1);
        self.going = self.going.and(next.bits_eq(self.c).not());
        self.c = V3::select(self.going, next, self.c);
        let q = closest_point_on_triangle(self.c, p0, p1, p2);
        self.q = V3::select(self.going, q, self.q);
    }

    /// The pair's decision from its closest points (`push_triangle_against`'s): the side
    /// memory it leaves where it pushes nothing (±1), or 0 where the scalar code must do
    /// it. `before` is the side memory as the pass found it.
    #[inline(always)]
    fn decide(&self, before: &[i8], out: &mut [i8], m: usize, push_pull: bool) {
        let zero = T::splat(0.0);
        let (one, minus_one) = (T::splat(1.0), T::splat(-1.0));
        let (c, q, normal, radius) = (self.c, self.q, self.normal, self.radius);
        let signed = normal.dot(c - self.corners[0]);
        let dist = (c - q).length();
        let off = c - normal * signed - q;
        let over_face = off.dot(off).lt(T::splat(1e-10));
        let current = T::select(zero.le(signed), one, minus_one);
        let mut was = F([0.0; LANES]);
        for l in 0..self.len {
            was.0[l] = f32::from(before[self.at + l * m]);
        }
        let was = T::of(was);
        let engaged = if push_pull {
            over_face.and(signed.abs().lt(T::splat(2.0) * radius))
        } else {
            <T::M as Mask>::NONE
        };
        let sigma = T::select(was.ne(zero), was, current);
        let violation = radius - sigma * signed;
        // Pushes: engaged and `!(violation <= 0)`, else `!(dist > radius)`.
        let pushes = engaged
            .and(violation.le(zero).not())
            .or(engaged.not().and(dist.gt(radius).not()));
        let close = self.close;
        let side = T::select(close, T::select(engaged, sigma, current), self.side_far);
        let (side, ask) = (side.f(), close.and(pushes).m());
        for l in 0..self.len {
            out[self.at + l * m] = if ask.0[l] != 0 {
                0
            } else if side.0[l] > 0.0 {
                1
            } else {
                -1
            };
        }
    }
}

/// The alternating projections of `a` and `b` (if any) to their fixed points (at most 4
/// rounds past the first), round by round together. A round in lanes no longer going
/// changes nothing, so each pair ends as it would alone.
#[inline(always)]
fn project_together<T: Lane>(a: &mut ClosePair<T>, mut b: Option<&mut ClosePair<T>>) {
    for _ in 0..4 {
        let a_going = a.going.any();
        let b_going = b.as_ref().is_some_and(|b| b.going.any());
        if !a_going && !b_going {
            break;
        }
        if a_going {
            a.project();
        }
        if let (true, Some(b)) = (b_going, b.as_mut()) {
            b.project();
        }
    }
}

/// glam's `Vec3::max_element` per lane: `max(x, max(y, z))` with `a > b ? a : b`.
#[inline(always)]
fn max_element<T: Lane>(v: V3<T>) -> T {
    let yz = T::select(v.y.gt(v.z), v.y, v.z);
    T::select(v.x.gt(yz), v.x, yz)
}

/// [`crate::math::closest_point_on_triangle`] per lane: every region's point computed,
/// the scalar function's choice made per lane in its order (vertex A, vertex B, edge AB,
/// vertex C, edge AC, edge BC, a degenerate triangle, the face).
#[inline(always)]
fn closest_point_on_triangle<T: Lane>(p: V3<T>, a: V3<T>, b: V3<T>, c: V3<T>) -> V3<T> {
    let zero = T::splat(0.0);
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    let mut done = d1.le(zero).and(d2.le(zero));
    let mut out = a;
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    // (A function, not a closure: see `collide::lanes::select_max`.)
    let take = take_where_open::<T>;
    take(&mut done, zero.le(d3).and(d4.le(d3)), b, &mut out);
    let vc = d1 * d4 - d3 * d2;
    let v = d1 / (d1 - d3);
    take(
        &mut done,
        vc.le(zero).and(zero.le(d1)).and(d3.le(zero)),
        a + ab * v,
        &mut out,
    );
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    take(&mut done, zero.le(d6).and(d5.le(d6)), c, &mut out);
    let vb = d5 * d2 - d1 * d6;
    let w = d2 / (d2 - d6);
    take(
        &mut done,
        vb.le(zero).and(zero.le(d2)).and(d6.le(zero)),
        a + ac * w,
        &mut out,
    );
    let va = d3 * d6 - d5 * d4;
    let (d43, d56) = (d4 - d3, d5 - d6);
    let w = d43 / (d43 + d56);
    take(
        &mut done,
        va.le(zero).and(zero.le(d43)).and(zero.le(d56)),
        b + (c - b) * w,
        &mut out,
    );
    let denom = va + vb + vc;
    take(&mut done, denom.abs().lt(T::splat(1e-30)), a, &mut out);
    let v = vb / denom;
    let w = vc / denom;
    take(
        &mut done,
        <T::M as Mask>::ALL,
        a + ab * v + ac * w,
        &mut out,
    );
    out
}

/// `out` takes `v` in the lanes of `m` not `done` yet, which are then done.
#[inline(always)]
fn take_where_open<T: Lane>(done: &mut T::M, m: T::M, v: V3<T>, out: &mut V3<T>) {
    let m = m.and(done.not());
    *out = V3::select(m, v, *out);
    *done = done.or(m);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::closest_point_on_triangle as scalar;
    use crate::rng::SplitMix64;

    /// The lanes' closest point on a triangle against the scalar function, bit for bit,
    /// with points in every region (vertices, edges, face), degenerate triangles (a
    /// point, a segment) and a point on a corner.
    #[test]
    fn closest_point_on_triangle_in_lanes_gives_the_scalar_bits() {
        let mut rng = SplitMix64::new(5);
        let mut u = |lo: f32, hi: f32| rng.range_f32(lo, hi);
        for round in 0..20_000 {
            let mut v = || Vec3::new(u(-1.0, 1.0), u(-1.0, 1.0), u(-1.0, 1.0));
            let (mut a, mut b, mut c, mut p) = (V3::ZERO, V3::ZERO, V3::ZERO, V3::ZERO);
            let mut want = [Vec3::ZERO; LANES];
            for l in 0..LANES {
                let (ta, mut tb, mut tc) = (v(), v(), v());
                let mut tp = v() * 2.0;
                match (round + l) % 11 {
                    0 => tb = ta,
                    1 => {
                        tb = ta;
                        tc = ta;
                    }
                    2 => tc = ta + (tb - ta) * 0.5,
                    3 => tp = ta,
                    _ => {}
                }
                a.set(l, ta);
                b.set(l, tb);
                c.set(l, tc);
                p.set(l, tp);
                want[l] = scalar(tp, ta, tb, tc);
            }
            let got = closest_point_on_triangle::<F>(p, a, b, c);
            for (l, w) in want.iter().enumerate() {
                assert!(
                    same_bits(got.get(l), *w),
                    "round {round}, lane {l}: {} vs {w}",
                    got.get(l)
                );
            }
        }
    }
}
