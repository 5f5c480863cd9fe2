//! One character's VRM spring bones with up to [`LANES`] springs side by side: the
//! specification's update of [`crate::dynamics::vrm::VrmJob`] (`update` in
//! `dynamics/vrm/job.rs`, the readable reference) with the links of different springs in
//! the lanes of one SIMD register, each lane repeating the scalar operations, so that the
//! results are the scalar path's bit for bit.
//!
//! **Why this order is the scalar order's result.** The scalar update visits links in
//! joint order and refreshes the model transforms lazily. A link reads its parent's and
//! its own model (both composed from the links above it), its centre's model and its own
//! state, and writes its rotation and model. So any order in which every link comes after
//! the links above it gives the same values. The plan holds the springs as *columns*
//! (each link's parent is the link before it in its column) and puts up to [`LANES`]
//! columns with the same centre in a *group*, whatever their colliders: the group tests a
//! list that holds each column's list in order, each entry masked to the lanes whose
//! list it is part of, which is each lane's own list in its own order ([`Merged`]). A
//! group's row `d` is the `d`-th link of each of its columns. A column that hangs below another column's link (a branching
//! spring) goes to a later group ([`Group`]s are in order of that depth).
//!
//! **What it does not take** (the job runs the scalar update instead, [`SpringLanes::new`]
//! says `None`): a link at a skeleton root, a link whose parent is a simulated joint's
//! descendant but not itself a link, a centre that a link can move, and a skeleton root
//! between the first and the last link (the scalar refresh takes a root's local as its
//! model there, the pose jobs compose it under the identity).

use super::contact::{collide_tail, Placed};
use crate::dynamics::vrm::job::update_link;
use crate::dynamics::vrm::{PlacedVrmCollider, VrmMode, VrmRig};
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx::Fa;
#[cfg(target_arch = "x86_64")]
use crate::lanes::avx512::Fz;
use crate::lanes::{rotation_arc_from_lanes, Lane, Mask, Trs, F, F4, LANES, M, Q, V3};
use crate::lanes::{Isa, SimdUse};
use crate::math::{normalize_or, Transform};
use crate::pose::compose_joints;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// How many springs a group puts side by side: [`LANES`], but four in WebAssembly, where
/// [`LANES`] (eight) is two `v128` registers and the portable type pays for all eight
/// lanes in a row whatever its springs fill; four are one register ([`F4`]). Measured
/// on the built-in avatar (13 springs, 44 joints; `web/bench/ab.mjs`): see
/// [`SpringLanes::update`].
pub(crate) const SPRING_LANES: usize = if cfg!(target_arch = "wasm32") {
    4
} else {
    LANES
};

/// The rig's links as lane rows, compiled once with the rig.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SpringLanes {
    /// Columns per group at most ([`SPRING_LANES`]): four or fewer run in [`F4`] where the
    /// portable type runs.
    width: usize,
    groups: Vec<Group>,
    /// Joints below a link that are not links, in skeleton order: the update leaves their
    /// models stale.
    below: Vec<usize>,
    /// Fixed mode's step pose: the joints whose step model the update or the colliders
    /// read before the update writes it (colliders' and centres' joints, the parents of
    /// the groups' first rows that are not links, and everything above them), in
    /// skeleton order.
    step_read: Vec<usize>,
    /// The links outside `step_read`: the update reads only their local translation and
    /// scale (it writes their rotation and model before anything reads them).
    step_links: Vec<usize>,
    /// The joints whose models the job reads from the models it is given, when no node
    /// constraint runs first: those no spring moves, and `step_read` (a collider or a
    /// centre may hang below a link), in skeleton order. Every other model the job
    /// writes before it reads it.
    input: Vec<usize>,
    /// Whether the lanes are worth their cost under [`SimdUse::Auto`]: at least 2.5 links
    /// a row on average. A lane row costs about what 2.5–3 scalar links cost (measured,
    /// AVX-512: the built-in avatar's 44 links in 12 rows, before groups merged their
    /// collider lists, lanes 1.5× faster than scalar; one spring of three links in three
    /// rows, lanes 1.3× slower).
    pays: bool,
}

/// Up to [`LANES`] columns with the same centre (each lane tests its own colliders).
#[derive(Debug, Clone, PartialEq)]
struct Group {
    center: Option<usize>,
    /// The colliders the group's links test, in order: their common list, or a list that
    /// holds each of theirs in order ([`Merged`]).
    colliders: Vec<usize>,
    /// With a merged list: per entry, the lanes whose links test it (see [`collide_tail`]).
    masks: Option<Vec<M>>,
    rows: Vec<Row>,
}

/// The `d`-th link of each column of a group, with its parameters per lane (computed
/// with the scalar code's own operations).
#[derive(Debug, Clone, PartialEq)]
struct Row {
    /// Lanes in use: columns are sorted longest first, so they are the first `n`. The
    /// other lanes repeat lane 0's link and are never written back.
    n: usize,
    link: [usize; LANES],
    joint: [usize; LANES],
    /// Each lane's parent joint (the first row reads its model from the pose; later rows
    /// take the row before's new models).
    parent: [usize; LANES],
    rest_local: Trs,
    /// The tail in the joint's rest local space.
    tail_local: V3,
    /// `rest_local.rotation * bone_axis`.
    rest_bone: V3,
    bone_axis: V3,
    /// `normalize_or(bone_axis, Y)` and its half-turn quaternion.
    arc_from: V3,
    half_turn: Q,
    /// `1 − drag_force`.
    keep: F,
    hit_radius: F,
    stiffness: F,
    gravity: V3,
    /// Lanes whose tail is a joint (three-vrm mode re-measures their length).
    tail_joint: M,
}

/// What one update reads and writes: the job's pose and its state's arrays.
pub(crate) struct SpringIo<'a> {
    pub(crate) component: Transform,
    pub(crate) dt: f32,
    pub(crate) mode: VrmMode,
    pub(crate) locals: &'a mut [Transform],
    pub(crate) models: &'a mut [Transform],
    pub(crate) placed: &'a [PlacedVrmCollider],
    /// Scratch, one per rig collider: the placed colliders in every lane.
    pub(crate) lane_placed: &'a mut [Placed],
    pub(crate) current_tail: &'a mut [Vec3],
    pub(crate) prev_tail: &'a mut [Vec3],
    pub(crate) length: &'a [f32],
    pub(crate) stale_tail: &'a [Vec3],
    pub(crate) rotation: &'a mut [Quat],
    /// The share of a step the update carries the motion and the forces by (the scalar
    /// job's `carry`: (1, 1) but in fixed mode's output step).
    pub(crate) carry: (f32, f32),
}

impl SpringIo<'_> {
    /// Every placed collider in every lane (`lane_placed`), for a pass over the groups.
    fn place_in_lanes(&mut self) {
        for (lp, p) in self.lane_placed.iter_mut().zip(self.placed) {
            *lp = placed_in_lanes(p);
        }
    }

    /// Row `d`'s parent models (the pose's for a group's first row, else `above`, the
    /// row before's new models) and its joints' locals.
    #[inline(always)]
    fn row_pose<T: Lane>(&self, row: &Row, d: usize, above: Trs<T>) -> (Trs<T>, Trs<T>) {
        let parent = if d == 0 {
            gather::<T>(self.models, &row.parent)
        } else {
            above
        };
        (parent, gather::<T>(self.locals, &row.joint))
    }
}

/// A column in the making: its links and how many columns it hangs below.
struct Column {
    links: Vec<usize>,
    level: usize,
}

impl SpringLanes {
    /// The plan for `rig`, or `None` where the lanes cannot give the scalar order's
    /// results (see the module's documentation) or there is nothing to simulate.
    pub(crate) fn new(sk: &Skeleton, rig: &VrmRig) -> Option<SpringLanes> {
        SpringLanes::with_width(sk, rig, SPRING_LANES)
    }

    /// [`SpringLanes::new`] with at most `width` (1..=[`LANES`]) columns a group.
    pub(crate) fn with_width(sk: &Skeleton, rig: &VrmRig, width: usize) -> Option<SpringLanes> {
        let width = width.clamp(1, LANES);
        let links = &rig.links;
        if rig.has_limits() {
            // Limits run in the scalar update (several springs side by side would apply
            // them lane by lane anyway); the crowd's lanes carry them (`frame.rs`).
            return None;
        }
        let (first, last) = (links.first()?.joint, links.last()?.joint);
        let n = sk.len();
        if (first + 1..=last).any(|k| sk.parent(k).is_none()) {
            return None;
        }
        let mut link_at = vec![None; n];
        for (i, l) in links.iter().enumerate() {
            if l.joint >= n || link_at[l.joint].is_some() {
                return None;
            }
            link_at[l.joint] = Some(i);
        }
        let mut affected = vec![false; n];
        for j in 0..n {
            affected[j] = link_at[j].is_some() || sk.parent(j).is_some_and(|p| affected[p]);
        }
        let colliders_of = |i: usize| &rig.link_colliders[links[i].colliders.clone()];
        // A column's links share their colliders and centre.
        let same_column = |a: usize, b: usize| {
            links[a].center == links[b].center && colliders_of(a) == colliders_of(b)
        };
        let mut columns: Vec<Column> = Vec::new();
        let mut column_of = vec![usize::MAX; links.len()];
        for (i, l) in links.iter().enumerate() {
            let p = l.parent?;
            if sk.parent(l.joint) != Some(p) || l.center.is_some_and(|c| affected[c]) {
                return None;
            }
            let level = match link_at[p] {
                Some(pi) => {
                    let c = column_of[pi];
                    if columns[c].links.last() == Some(&pi) && same_column(pi, i) {
                        columns[c].links.push(i);
                        column_of[i] = c;
                        continue;
                    }
                    columns[c].level + 1
                }
                // A parent below a link that is not a link itself: its model would need
                // the lazy refresh's order.
                None if affected[p] => return None,
                None => 0,
            };
            column_of[i] = columns.len();
            columns.push(Column {
                links: vec![i],
                level,
            });
        }
        // Shallow levels first; within one, by centre, longest first (so that a row's
        // lanes in use are a prefix). Then each column joins the group before it when it
        // has the same level and centre, a lane is free and the group's merged collider
        // list costs less than a group of its own would (see `Merged::take`).
        let mut order: Vec<usize> = (0..columns.len()).collect();
        order.sort_by(|&a, &b| {
            let (ca, cb) = (&columns[a], &columns[b]);
            (ca.level, links[ca.links[0]].center)
                .cmp(&(cb.level, links[cb.links[0]].center))
                .then(cb.links.len().cmp(&ca.links.len()))
        });
        let mut groups = Vec::new();
        let mut start = 0;
        while start < order.len() {
            let head = &columns[order[start]];
            let mut merged = Merged::new(colliders_of(head.links[0]));
            let mut end = start + 1;
            while end < order.len() && end - start < width {
                let c = &columns[order[end]];
                let l = c.links[0];
                if c.level != head.level
                    || links[l].center != links[head.links[0]].center
                    || !merged.take(colliders_of(l), head.links.len(), c.links.len())
                {
                    break;
                }
                end += 1;
            }
            let members: Vec<&Column> = order[start..end].iter().map(|&c| &columns[c]).collect();
            groups.push(Group::new(sk, rig, &members, merged));
            start = end;
        }
        let below = (0..n)
            .filter(|&j| affected[j] && link_at[j].is_none())
            .collect();
        // What a step reads of its interpolated pose before the update writes it.
        let mut read = vec![false; n];
        for &(j, _) in &rig.colliders {
            read[j] = true;
        }
        for l in links {
            if let Some(c) = l.center {
                read[c] = true;
            }
            if let Some(p) = l.parent.filter(|&p| link_at[p].is_none()) {
                read[p] = true;
            }
        }
        for j in (0..n).rev() {
            if let (true, Some(p)) = (read[j], sk.parent(j)) {
                read[p] = true;
            }
        }
        let step_read = (0..n).filter(|&j| read[j]).collect();
        let input = (0..n).filter(|&j| read[j] || !affected[j]).collect();
        let step_links = links
            .iter()
            .map(|l| l.joint)
            .filter(|&j| !read[j])
            .collect();
        let rows: usize = groups.iter().map(|g: &Group| g.rows.len()).sum();
        Some(SpringLanes {
            width,
            groups,
            below,
            step_read,
            step_links,
            input,
            pays: 2 * links.len() >= 5 * rows,
        })
    }

    /// The models of [`SpringLanes`]' input joints from `locals`, as
    /// [`crate::pose::LocalToModelJob`] composes them (a root under the identity): all the
    /// lane path reads of the models it is given. The others are left as they were.
    pub(crate) fn compose_input(
        &self,
        sk: &Skeleton,
        locals: &[Transform],
        models: &mut [Transform],
    ) {
        let input = self.input.iter().copied();
        compose_joints(sk, input, Some(&Transform::IDENTITY), locals, models);
    }

    /// Fixed mode's step pose at `w` between last frame's locals `prev` and this frame's
    /// `now`, as far as a step reads it: `step_locals` and `step_models` as the whole
    /// pose's lerp and refresh give them (a root taking its local as its model) for the
    /// joints the step reads, and the links' local translations and scales; the rest is
    /// left as it was (the update writes the links' rotations and models before reading
    /// them, and nothing in a step reads the joints below the links).
    pub(crate) fn step_pose(
        &self,
        sk: &Skeleton,
        (prev, now): (&[Transform], &[Transform]),
        w: f32,
        step_locals: &mut [Transform],
        step_models: &mut [Transform],
        isa: Isa,
    ) {
        if w >= 1.0 {
            // A step that ends on the frame takes the frame's pose (the scalar job's).
            for &j in self.step_read.iter().chain(&self.step_links) {
                step_locals[j] = now[j];
            }
        } else {
            crate::lanes::lerp_transforms_at(prev, now, w, &self.step_read, step_locals, isa);
        }
        let read = self.step_read.iter().copied();
        compose_joints(sk, read, None, step_locals, step_models);
        if w < 1.0 {
            for &j in &self.step_links {
                // `Transform::lerp`'s translation and scale.
                step_locals[j].translation = prev[j].translation.lerp(now[j].translation, w);
                step_locals[j].scale = prev[j].scale.lerp(now[j].scale, w);
            }
        }
    }

    /// After an update: the models of the joints below the links, from their parents'
    /// (every such joint has a parent, and parents come first). With the links' models
    /// written by the update and the other joints' untouched, `models` is then the model
    /// pose of `locals` as [`crate::pose::LocalToModelJob`] computes it, bit for bit,
    /// when it was before the update.
    pub(crate) fn refresh_below(
        &self,
        sk: &Skeleton,
        locals: &[Transform],
        models: &mut [Transform],
    ) {
        // (Every joint below a link has a parent: the root rule never applies.)
        compose_joints(sk, self.below.iter().copied(), None, locals, models);
    }

    /// Whether the job runs this plan under `simd`: never for [`SimdUse::Scalar`], always
    /// for a lane type asked for by name (to test and measure it), and under
    /// [`SimdUse::Auto`] where it pays (the scalar update is faster for a few springs in
    /// a row: the same bits either way).
    pub(crate) fn runs_with(&self, simd: SimdUse) -> bool {
        match simd {
            SimdUse::Scalar => false,
            SimdUse::Auto => self.pays,
            SimdUse::Portable | SimdUse::Avx2 => true,
        }
    }

    /// How many lane groups the update runs.
    pub(crate) fn groups(&self) -> usize {
        self.groups.len()
    }

    /// The scalar update's results for every link (its tails, rotations, and the links'
    /// local rotations and model transforms in the pose; other joints' models are left
    /// as they were, the job recomputes them), computed in the lane type `isa` chose.
    ///
    /// A row with few lanes in use costs a whole row: such rows (and the rest of their
    /// group) run link by link with the scalar update instead, at or below a number of
    /// lanes measured per lane type on the built-in avatar (`tassel bench demo.vrm --vrm
    /// fixed --simd auto|avx2|portable`, thresholds 0-4 alternating; `web/bench/ab.mjs`
    /// for the WebAssembly build): 1 of 16 with AVX-512 (90-95 against 102-122 ns per
    /// joint-step with none; 2 was slower), 3 of 16 with AVX2 (97 against 119-123), a
    /// quarter of the portable type's lanes natively (a test path there).
    ///
    /// A plan of at most four columns a group ([`SPRING_LANES`] in WebAssembly) runs in
    /// the four-lane type [`F4`] where the portable type would run, with rows of one lane
    /// in use link by link: on the built-in avatar its 13 springs take four groups of
    /// one `v128` register each instead of two of eight lanes (two registers) with rows
    /// of two scalar (the previous WebAssembly plan: 9-12 % less time per frame than
    /// none). `web/bench/ab.mjs 10|1 fixed manager`, both orders, one process: 2-14 %
    /// less time per frame of the web manager than that plan.
    pub(crate) fn update(&self, rig: &VrmRig, io: &mut SpringIo<'_>, isa: Isa) {
        // SAFETY (both): the function only requires the instructions of its lane type,
        // and `Isa::of` chose that type because the CPU has them.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        match isa {
            Isa::Avx512 => return unsafe { self.update_avx512(rig, io) },
            Isa::Avx2 => return unsafe { self.update_avx2(rig, io) },
            Isa::Portable => {}
        }
        let _ = isa;
        if self.width <= 4 {
            return self.update_narrow(rig, io);
        }
        self.update_baseline(rig, io)
    }

    #[inline(never)]
    fn update_narrow(&self, rig: &VrmRig, io: &mut SpringIo<'_>) {
        self.update_lanes::<F4>(rig, io, 1)
    }

    #[inline(never)]
    fn update_baseline(&self, rig: &VrmRig, io: &mut SpringIo<'_>) {
        self.update_lanes::<F>(rig, io, LANES / 4)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[inline(never)]
    fn update_avx2(&self, rig: &VrmRig, io: &mut SpringIo<'_>) {
        // The explicit AVX2 lane type only inside this function, after the CPU was found
        // to have AVX2 (the condition of its soundness, `lanes/avx.rs`).
        self.update_lanes::<Fa>(rig, io, 3)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    #[inline(never)]
    fn update_avx512(&self, rig: &VrmRig, io: &mut SpringIo<'_>) {
        // The explicit AVX-512 lane type only inside this function, after the CPU was
        // found to have it (the condition of its soundness, `lanes/avx512.rs`).
        self.update_lanes::<Fz>(rig, io, 1)
    }

    /// The update in lanes of type `T`; the rows with at most `scalar_rows` lanes in use
    /// run link by link with the scalar update instead (the same bits: each link's update
    /// reads only its own state, its parent's model and the colliders).
    #[inline(always)]
    fn update_lanes<T: Lane>(&self, rig: &VrmRig, io: &mut SpringIo<'_>, scalar_rows: usize) {
        let comp = Trs::<T>::of(&Trs::splat(&io.component));
        let dt = T::splat(io.dt);
        let (carry_motion, carry_force) = (T::splat(io.carry.0), T::splat(io.carry.1));
        let exact = io.mode == VrmMode::Fixed;
        let three_vrm = io.mode == VrmMode::ThreeVrm;
        io.place_in_lanes();
        for g in &self.groups {
            // The scalar code's `component * models[c]`, the same for every lane.
            let center = match g.center {
                Some(c) => Some(Trs::<T>::of(&Trs::splat(&(io.component * io.models[c])))),
                None => None,
            };
            let mut above = Trs::<T>::of(&Trs::splat(&Transform::IDENTITY));
            for (d, row) in g.rows.iter().enumerate() {
                if row.n <= scalar_rows {
                    // This row and the rest of the group (no wider: columns are sorted
                    // longest first) link by link with the scalar update, each link's
                    // model first made fresh as the scalar update's refresh makes it.
                    for row in &g.rows[d..] {
                        for l in 0..row.n {
                            let (j, p) = (row.joint[l], row.parent[l]);
                            io.models[j] = io.models[p] * io.locals[j];
                            update_link(rig, io, row.link[l]);
                        }
                    }
                    break;
                }
                let (parent, local) = io.row_pose(row, d, above);
                let parent_world = comp.mul(&parent);
                // The joint's model translation (`models[p] * locals[j]`), then world.
                let own_t = parent.transform_point(local.t);
                let position = comp.transform_point(own_t);
                let mut stored = (V3::splat(Vec3::ZERO), V3::splat(Vec3::ZERO));
                let mut length = F::splat(0.0);
                for l in 0..T::WIDTH {
                    let i = row.link[l];
                    stored.0.set(l, io.current_tail[i]);
                    stored.1.set(l, io.prev_tail[i]);
                    length.0[l] = io.length[i];
                }
                let (current_stored, prev_stored) = (V3::<T>::of(stored.0), V3::<T>::of(stored.1));
                let (current, prev) = match &center {
                    Some(c) => (
                        c.transform_point(current_stored),
                        c.transform_point(prev_stored),
                    ),
                    None => (current_stored, prev_stored),
                };
                let rest_dir = parent_world.r.mul_vec3(V3::of(row.rest_bone));
                let inertia = (current - prev) * T::of(row.keep) * carry_motion;
                let stiffness = rest_dir * (T::of(row.stiffness) * dt) * carry_force;
                let external = V3::<T>::of(row.gravity) * dt * carry_force;
                let mut length = T::of(length);
                if three_vrm {
                    let mut stale = V3::splat(Vec3::ZERO);
                    for l in 0..T::WIDTH {
                        stale.set(l, io.stale_tail[row.link[l]]);
                    }
                    let measured = (V3::<T>::of(stale) - position).length();
                    length = T::select(<T::M as Mask>::of(row.tail_joint), measured, length);
                }
                let next = position
                    + (current + inertia + stiffness + external - position).normalize_or(rest_dir)
                        * length;
                let (next, _) = collide_tail(
                    &g.colliders,
                    g.masks.as_deref(),
                    &rig.colliders,
                    io.lane_placed,
                    T::of(row.hit_radius),
                    position,
                    length,
                    rest_dir,
                    next,
                    exact,
                    None,
                );
                let new_stored = match &center {
                    Some(c) => c.inverse_transform_point(next),
                    None => next,
                };
                let rotation = row.turn(&parent_world, next);
                // `models[p] * locals[j]` with the new rotation; its translation is `own_t`.
                let model = Trs {
                    t: own_t,
                    r: parent.r.mul_quat(rotation).normalize(),
                    s: parent.s * local.s,
                };
                let (new_stored, rotation_f, model_f) = (new_stored.f(), rotation.f(), model.f());
                for l in 0..row.n {
                    let (i, j) = (row.link[l], row.joint[l]);
                    io.prev_tail[i] = io.current_tail[i];
                    io.current_tail[i] = new_stored.get(l);
                    io.rotation[i] = rotation_f.get(l);
                    io.locals[j].rotation = rotation_f.get(l);
                    io.models[j] = model_f.get(l);
                }
                above = model;
            }
        }
    }
}

impl Group {
    fn new(sk: &Skeleton, rig: &VrmRig, columns: &[&Column], merged: Merged) -> Group {
        let head = &rig.links[columns[0].links[0]];
        let depth = columns.iter().map(|c| c.links.len()).max().unwrap_or(0);
        let rows = (0..depth)
            .map(|d| {
                let n = columns.iter().take_while(|c| c.links.len() > d).count();
                let mut link = [columns[0].links[d]; LANES];
                for (l, c) in columns.iter().take(n).enumerate() {
                    link[l] = c.links[d];
                }
                Row::new(sk, rig, n, link)
            })
            .collect();
        // One list for all lanes, or the merged list with a mask per entry: the lanes
        // whose own list took that entry (lanes past the columns repeat lane 0's links,
        // are never written back, and take its list).
        let same = merged.places.iter().all(|p| p.len() == merged.list.len());
        let masks = (!same).then(|| {
            (0..merged.list.len())
                .map(|k| {
                    M::from_bools(std::array::from_fn(|l| {
                        merged.places[if l < columns.len() { l } else { 0 }].contains(&k)
                    }))
                })
                .collect()
        });
        Group {
            center: head.center,
            colliders: merged.list,
            masks,
            rows,
        }
    }
}

/// A group's colliders: one list that holds every column's list as a subsequence (the
/// shortest common supersequence of two lists, by their longest common subsequence, taken
/// column by column), and where each column's entries are in it. A lane that tests the
/// entries at its places, in order, tests its own list in its own order.
#[derive(Debug, Clone, PartialEq)]
struct Merged {
    list: Vec<usize>,
    places: Vec<Vec<usize>>,
}

impl Merged {
    fn new(first: &[usize]) -> Merged {
        Merged {
            list: first.to_vec(),
            places: vec![(0..first.len()).collect()],
        }
    }

    /// Takes a column's list `b` when the group's cost, `rows` rows each testing the
    /// merged list, grows by less than a group of its own of `b_rows` rows would cost (a
    /// row's own work counted as four collider tests). Leaves `self` as it was otherwise.
    fn take(&mut self, b: &[usize], rows: usize, b_rows: usize) -> bool {
        let (list, at_a, at_b) = supersequence(&self.list, b);
        let added = list.len() - self.list.len();
        if added * rows > b_rows * (4 + b.len()) {
            return false;
        }
        for p in &mut self.places {
            for k in p.iter_mut() {
                *k = at_a[*k];
            }
        }
        self.places.push(at_b);
        self.list = list;
        true
    }
}

/// A shortest common supersequence of `a` and `b` (the longest common subsequence taken
/// once, the rest of each in order), with where each entry of `a` and of `b` went in it.
fn supersequence(a: &[usize], b: &[usize]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let (n, m) = (a.len(), b.len());
    // lcs[i][j]: the longest common subsequence of a[i..] and b[j..].
    let mut lcs = vec![vec![0usize; m + 1]; n + 1];
    for i in (0..n).rev() {
        for j in (0..m).rev() {
            lcs[i][j] = if a[i] == b[j] {
                lcs[i + 1][j + 1] + 1
            } else {
                lcs[i + 1][j].max(lcs[i][j + 1])
            };
        }
    }
    let (mut out, mut at_a, mut at_b) = (Vec::new(), Vec::new(), Vec::new());
    let (mut i, mut j) = (0, 0);
    while i < n || j < m {
        if i < n && j < m && a[i] == b[j] {
            at_a.push(out.len());
            at_b.push(out.len());
            out.push(a[i]);
            i += 1;
            j += 1;
        } else if j == m || (i < n && lcs[i + 1][j] >= lcs[i][j + 1]) {
            at_a.push(out.len());
            out.push(a[i]);
            i += 1;
        } else {
            at_b.push(out.len());
            out.push(b[j]);
            j += 1;
        }
    }
    (out, at_a, at_b)
}

impl Row {
    /// The local rotations that point the lanes' bones at `tail` (world): the rest local
    /// rotation turned from the bone axis to the tail seen from the rest frame under the
    /// parent (the scalar `turn_toward`).
    #[inline(always)]
    fn turn<T: Lane>(&self, parent_world: &Trs<T>, tail: V3<T>) -> Q<T> {
        let rest_local = Trs::<T>::of(&self.rest_local);
        let rest_world = parent_world.mul(&rest_local);
        let to = rest_world
            .inverse_transform_point(tail)
            .normalize_or(V3::of(self.bone_axis));
        let arc = rotation_arc_from_lanes(V3::of(self.arc_from), Q::of(self.half_turn), to);
        rest_local.r.mul_quat(arc).normalize()
    }

    fn new(sk: &Skeleton, rig: &VrmRig, n: usize, link: [usize; LANES]) -> Row {
        let id = Trs::splat(&Transform::IDENTITY);
        let zero = V3::splat(Vec3::ZERO);
        let mut row = Row {
            n,
            link,
            joint: [0; LANES],
            parent: [0; LANES],
            rest_local: id,
            tail_local: zero,
            rest_bone: zero,
            bone_axis: zero,
            arc_from: zero,
            half_turn: Q::splat(Quat::IDENTITY),
            keep: F::splat(0.0),
            hit_radius: F::splat(0.0),
            stiffness: F::splat(0.0),
            gravity: zero,
            tail_joint: M::from_bools([false; LANES]),
        };
        let mut tail_joint = [false; LANES];
        for (lane, &i) in link.iter().enumerate() {
            let l = &rig.links[i];
            row.joint[lane] = l.joint;
            row.parent[lane] = sk.parent(l.joint).unwrap_or(0);
            row.rest_local.set(lane, &l.rest_local);
            row.tail_local.set(lane, l.tail_local);
            row.rest_bone.set(lane, l.rest_local.rotation * l.bone_axis);
            row.bone_axis.set(lane, l.bone_axis);
            let a = normalize_or(l.bone_axis, Vec3::Y);
            let o = a.any_orthonormal_vector();
            row.arc_from.set(lane, a);
            row.half_turn.set(lane, Quat::from_xyzw(o.x, o.y, o.z, 0.0));
            row.keep.0[lane] = 1.0 - l.drag_force;
            row.hit_radius.0[lane] = l.hit_radius;
            row.stiffness.0[lane] = l.stiffness;
            row.gravity.set(lane, l.gravity);
            tail_joint[lane] = l.tail_joint.is_some();
        }
        row.tail_joint = M::from_bools(tail_joint);
        row
    }
}

/// `transforms[index[l]]` in lane `l` ([`Lane::transforms`]).
#[inline(always)]
fn gather<T: Lane>(transforms: &[Transform], index: &[usize; LANES]) -> Trs<T> {
    T::transforms(&std::array::from_fn(|l| &transforms[index[l]]))
}

/// A scalar placed collider in every lane (with the bounding sphere of the crowd's quick
/// rejection, computed as the crowd does).
fn placed_in_lanes(p: &PlacedVrmCollider) -> Placed {
    let zero = V3::splat(Vec3::ZERO);
    match *p {
        PlacedVrmCollider::Sphere { center, .. } => Placed {
            a: V3::splat(center),
            b: zero,
            mid: V3::splat(center),
            half: F::splat(0.0),
        },
        PlacedVrmCollider::Capsule { head, tail, .. } => {
            let (a, b) = (V3::splat(head), V3::splat(tail));
            let half = F::splat(0.5);
            Placed {
                a,
                b,
                mid: (a + b) * half,
                half: (b - a).length() * half,
            }
        }
        PlacedVrmCollider::Plane { point, normal } => Placed {
            a: V3::splat(point),
            b: V3::splat(normal),
            mid: V3::splat(point),
            half: F::splat(0.0),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::{supersequence, Merged, SpringLanes};
    use crate::dynamics::vrm::{
        VrmCollider, VrmColliderGroup, VrmMode, VrmOptions, VrmShape, VrmSpringBones,
    };
    use crate::dynamics::RigSettings;
    use crate::lanes::SimdUse;
    use crate::{CharacterRig, CharacterSim, Transform};
    use glam::{Quat, Vec3};
    use std::sync::Arc;

    /// The built-in avatar's springs with more of the plan in use: the ponytail and the
    /// locks keep their tails in the head's space (a centre), the skirt also has a plane
    /// under the hips and an inside sphere around them (every shape, inside and out).
    fn avatar_bones() -> (crate::Skeleton, VrmSpringBones) {
        let c = crate::builtin::character();
        let sk = c.skeleton.clone();
        let mut b = crate::builtin::avatar::spring_bones(&c);
        let head = sk.find("head").unwrap();
        let hips = sk.find("hips").unwrap();
        for s in &mut b.springs {
            if s.name == "ponytail" || s.name.starts_with("lock") {
                s.center = Some(head);
            }
        }
        for shape in [
            VrmShape::Plane {
                offset: Vec3::new(0.0, -0.55, 0.0),
                normal: Vec3::Y,
            },
            VrmShape::Sphere {
                offset: Vec3::ZERO,
                radius: 0.5,
                inside: true,
            },
        ] {
            b.colliders.push(VrmCollider { joint: hips, shape });
            b.collider_groups.push(VrmColliderGroup {
                name: format!("extra {}", b.colliders.len()),
                colliders: vec![b.colliders.len() - 1],
            });
            let g = b.collider_groups.len() - 1;
            for s in b.springs.iter_mut().filter(|s| s.name.starts_with("skirt")) {
                s.collider_groups.push(g);
            }
        }
        (sk, b)
    }

    /// The four-lane plan (WebAssembly's) run natively in the four-lane type against the
    /// scalar update: every local and model transform the same bits after every frame, in
    /// every mode, through a sway, a pause, a hitch and a teleport.
    #[test]
    fn four_lanes_a_group_give_the_scalar_bits() {
        let (sk, bones) = avatar_bones();
        let modes = [
            (VrmMode::Spec, 60.0),
            (VrmMode::ThreeVrm, 60.0),
            (VrmMode::Fixed, 60.0),
            (VrmMode::Fixed, 90.0),
        ];
        for (mode, step_rate) in modes {
            let options = VrmOptions {
                mode,
                step_rate,
                teleport_distance: 2.0,
                ..Default::default()
            };
            let rig = CharacterRig::with_vrm(sk.clone(), &RigSettings::default(), &bones, options)
                .unwrap();
            let mut narrow = rig.clone();
            let plan = SpringLanes::with_width(&sk, &narrow.vrm, 4).expect("a lane plan");
            assert!(plan.groups.iter().all(|g| g.rows.iter().all(|r| r.n <= 4)));
            assert!(plan.groups.len() >= 4, "13 springs, four a group");
            assert!(
                plan.groups.iter().any(|g| g.masks.is_some()),
                "a merged list"
            );
            assert!(plan.groups.iter().any(|g| g.center.is_some()), "a centre");
            narrow.vrm.lanes = Some(plan);
            let mut reference = CharacterSim::from_rig(Arc::new(rig));
            reference.set_simd(SimdUse::Scalar);
            let mut sim = CharacterSim::from_rig(Arc::new(narrow));
            sim.set_simd(SimdUse::Portable);
            let swing = sk.find("hips").unwrap();
            let mut locals = sk.rest().to_vec();
            let mut turned = 0.0f32;
            for f in 0..400 {
                let t = f as f32 / 60.0;
                locals.copy_from_slice(sk.rest());
                locals[swing].rotation =
                    sk.rest()[swing].rotation * Quat::from_rotation_x(0.6 * (3.0 * t + 1.0).sin());
                let jump = if f >= 300 { 10.0 } else { 0.0 };
                let root = Transform::from_translation_rotation(
                    Vec3::new((3.0 * t).sin() * 0.5 + jump, 0.1 * (5.0 * t).sin(), t),
                    Quat::from_rotation_y(0.8 * (2.0 * t).sin()),
                );
                let dt = match f {
                    100 => 0.0,
                    200 => 0.25,
                    _ => 1.0 / 60.0,
                };
                let want = reference.frame(&locals, root, dt).unwrap().clone();
                let got = sim.frame(&locals, root, dt).unwrap();
                for j in 0..sk.len() {
                    let bits = |t: &Transform| {
                        (
                            t.translation.to_array().map(f32::to_bits),
                            t.rotation.to_array().map(f32::to_bits),
                            t.scale.to_array().map(f32::to_bits),
                        )
                    };
                    assert_eq!(
                        (bits(&got.locals[j]), bits(&got.models[j])),
                        (bits(&want.locals[j]), bits(&want.models[j])),
                        "{mode:?} at {step_rate} Hz: frame {f}, joint '{}'",
                        sk.name(j)
                    );
                }
                for l in &reference.vrm().links {
                    let turn = want.locals[l.joint]
                        .rotation
                        .angle_between(l.rest_local.rotation);
                    turned = turned.max(turn);
                }
            }
            assert!(turned > 0.05, "{mode:?}: the springs barely moved");
        }
    }

    /// Every pair of short lists over three colliders (repeats allowed): the result holds
    /// each list at its places, in order, and is as long as the two less their longest
    /// common subsequence (counted here by brute force over the subsequences of `a`).
    #[test]
    fn supersequence_holds_both_lists_and_is_shortest() {
        let lists: Vec<Vec<usize>> = (0..40usize)
            .map(|x| {
                let len = x % 4;
                (0..len).map(|i| (x / 4 + i * 2) % 3).collect()
            })
            .collect();
        let is_sub = |s: &[usize], t: &[usize]| {
            let mut it = t.iter();
            s.iter().all(|x| it.any(|y| y == x))
        };
        for a in &lists {
            for b in &lists {
                let (out, at_a, at_b) = supersequence(a, b);
                for (list, at) in [(a, &at_a), (b, &at_b)] {
                    assert_eq!(at.len(), list.len());
                    assert!(at.windows(2).all(|w| w[0] < w[1]), "{a:?} {b:?}");
                    for (k, &p) in at.iter().enumerate() {
                        assert_eq!(out[p], list[k]);
                    }
                }
                let lcs = (0..1usize << a.len())
                    .map(|bits| {
                        let sub: Vec<usize> = (0..a.len())
                            .filter(|i| bits >> i & 1 == 1)
                            .map(|i| a[i])
                            .collect();
                        if is_sub(&sub, b) {
                            sub.len()
                        } else {
                            0
                        }
                    })
                    .max()
                    .unwrap_or(0);
                assert_eq!(out.len(), a.len() + b.len() - lcs, "{a:?} {b:?} -> {out:?}");
            }
        }
    }

    #[test]
    fn a_column_joins_while_it_costs_less_than_a_group_of_its_own() {
        // Rows of the group 7: a list of one new collider costs 7 tests, a group of its
        // own of 3 rows 3 x (4 + 1) = 15: taken.
        let mut m = Merged::new(&[2, 4, 3, 5]);
        assert!(m.take(&[0], 7, 3));
        // Nothing in common: the group's list first (ties take it), then the new one.
        assert_eq!(m.list, [2, 4, 3, 5, 0]);
        assert_eq!(m.places, vec![vec![0, 1, 2, 3], vec![4]]);
        // Five new colliders on a 1-row column: 5 x 7 = 35 > 1 x (4 + 5): refused, and
        // the group is as it was.
        let before = m.clone();
        assert!(!m.take(&[10, 11, 12, 13, 14], 7, 1));
        assert_eq!(m, before);
    }
}
