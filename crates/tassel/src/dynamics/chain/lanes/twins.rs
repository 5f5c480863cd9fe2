//! One character's bone chains in SIMD lanes: up to [`LANES`] *twin* chains (the same
//! points, per-point parameters, settings and collider list; hair strands, skirt chains,
//! a fan of ribbons) side by side, one chain per lane, stepped by the lane step
//! ([`super::step`], through the lane-group frame [`super::Ctx`]).
//!
//! The chain crowd's lanes are characters running the same chain; here they are chains
//! of one character. The crowd's frame of one chain needs nothing else: each lane has
//! its own points, targets, colliders (here the same placed colliders in every lane),
//! character path (here the same), reset flags, step counts and wind generator, and a
//! chain's frame reads nothing of another chain's. So a group gives each of its chains
//! the bits the scalar job ([`crate::dynamics::chain::ChainJob`]) gives it: the scalar
//! job is the readable reference ([`crate::lanes::SimdUse::Scalar`]) the lanes are
//! tested against.

pub(crate) use super::frame::LaneFrame;
use super::frame::{any_planar, Ctx};
use super::pack::{Pack, Scratch};
use super::step::LaneShape;
use crate::collide::lanes::Bound;
use crate::collide::PlacedCollider;
use crate::dynamics::chain::compile::{ChainRig, CompiledChain, NONE};
use crate::dynamics::path::CharacterPath;
use crate::lanes::{rotation_arc, Isa, Lane, Mask, Trs, F, LANES, M, Q, V3};
use crate::math::Transform;
use crate::rng::SplitMix64;
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};

/// A chain without a twin runs the scalar step (a group of one would pay eight lanes'
/// arithmetic for one chain). Groups of two and more run in lanes; whether two or three
/// twins gain over the scalar step has not been measured (the bench rig has groups of
/// eight).
const MIN_TWINS: usize = 2;

/// Twin chains of a rig, stepped together: lane `l` is `chains[l]`.
#[derive(Debug, Clone)]
pub(crate) struct ChainLaneGroup {
    /// The chains, in rig order (2..=[`LANES`]).
    pub chains: Vec<usize>,
    /// The first chain as a rig of its own: its points from 0 (parents rebased), its
    /// settings and collider list, every collider of the rig.
    pub rig: ChainRig,
    /// Each rig collider's shape as the lanes see it.
    pub(super) shapes: Vec<LaneShape>,
    /// The write-back of the group's rotator joints in lanes (`None`: a rotator's parent
    /// joint is another chain's rotator, whose turn it would have to wait for; the scalar
    /// write-back does those).
    pub write_back: Option<Vec<LaneRotator>>,
}

/// The `k`th rotator joint of every chain of a group (twins have theirs at the same
/// points).
#[derive(Debug, Clone)]
pub(crate) struct LaneRotator {
    /// Its joint per lane.
    joints: [u32; LANES],
    /// Its point and its children's points, from the chain's first point.
    point: usize,
    kids: Vec<usize>,
    /// Whose model rotation its local rotation is relative to.
    parent: RotatorParent,
}

/// One rotator row of the lanes' write-back between its two passes.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TurnedRow {
    /// The row's new model rotation (where not `skip`).
    new_rot: Q,
    /// What the row's children see as their parent's model rotation: the new one, or the
    /// animated one where the row is skipped.
    turned: Q,
    /// The lanes left as animated (no direction to turn from or toward).
    skip: M,
}

#[derive(Debug, Clone, Copy)]
enum RotatorParent {
    /// The group's rotator of this index (earlier in the list): its new rotation.
    Rotator(usize),
    /// A joint no chain turns, per lane: its animated model rotation.
    Joint([u32; LANES]),
    /// None (a skeleton root): the identity.
    Root,
}

/// The lane groups of `rig`: chains that do not collide with the world (the lanes have no
/// level), grouped in rig order with their twins, groups of at least [`MIN_TWINS`].
pub(crate) fn plan(sk_parent: &[Option<usize>], rig: &ChainRig) -> Vec<ChainLaneGroup> {
    let mut groups: Vec<Vec<usize>> = Vec::new();
    // Each key's group still open (fewer than LANES chains): one look-up per chain.
    let mut open: std::collections::HashMap<_, usize> = std::collections::HashMap::new();
    for ci in 0..rig.chains.len() {
        // Chains joined by bone constraints step with their group; sync bones move targets
        // the lanes do not read.
        if rig.chains[ci].settings.world_collision || rig.steps_outside_lanes(ci) {
            continue;
        }
        let key = twin_key(rig, ci);
        match open.get(&key).copied() {
            Some(g) if groups[g].len() < LANES => groups[g].push(ci),
            _ => {
                open.insert(key, groups.len());
                groups.push(vec![ci]);
            }
        }
    }
    let tables = RotatorTables::of(sk_parent, rig);
    groups
        .into_iter()
        .filter(|g| g.len() >= MIN_TWINS)
        .map(|chains| {
            let one = one_chain(rig, chains[0]);
            let shapes = one
                .colliders
                .iter()
                .map(|c| LaneShape::of(c.shape))
                .collect();
            ChainLaneGroup {
                write_back: lane_rotators(sk_parent, rig, &tables, &chains),
                chains,
                rig: one,
                shapes,
            }
        })
        .collect()
}

/// The rig's rotators by joint and by chain (in joint order).
struct RotatorTables {
    of_joint: Vec<Option<usize>>,
    of_chain: Vec<Vec<usize>>,
}

impl RotatorTables {
    fn of(sk_parent: &[Option<usize>], rig: &ChainRig) -> RotatorTables {
        let mut t = RotatorTables {
            of_joint: vec![None; sk_parent.len()],
            of_chain: vec![Vec::new(); rig.chains.len()],
        };
        for (r, (j, p, _)) in rig.rotators.iter().enumerate() {
            t.of_joint[*j as usize] = Some(r);
            t.of_chain[rig.chain_of[*p as usize] as usize].push(r);
        }
        t
    }
}

/// The rotators of the twin `chains` lined up by index, or `None` when one's parent joint
/// is a rotator of another chain (or of its own chain in a way the twins do not share).
fn lane_rotators(
    sk_parent: &[Option<usize>],
    rig: &ChainRig,
    tables: &RotatorTables,
    chains: &[usize],
) -> Option<Vec<LaneRotator>> {
    let rotator_of_joint = |j: usize| tables.of_joint[j];
    // Each chain's rotators, in joint order.
    let per_chain: Vec<&Vec<usize>> = chains.iter().map(|&ci| &tables.of_chain[ci]).collect();
    let count = per_chain[0].len();
    if per_chain.iter().any(|r| r.len() != count) {
        return None;
    }
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let mut joints = [0u32; LANES];
        let mut parents = [0u32; LANES];
        // (point, children, parent: none / a joint no chain turns / this chain's rotator k')
        let mut shape: Option<(usize, Vec<usize>, Option<Option<usize>>)> = None;
        for (l, &ci) in chains.iter().enumerate() {
            let start = rig.chains[ci].points.start;
            let (j, p, kids) = &rig.rotators[per_chain[l][k]];
            let j = *j as usize;
            let kids: Vec<usize> = rig.rotator_children[kids.start as usize..kids.end as usize]
                .iter()
                .map(|&c| c as usize - start)
                .collect();
            let parent = match sk_parent[j] {
                None => None,
                Some(q) => {
                    parents[l] = q as u32;
                    match rotator_of_joint(q) {
                        None => Some(None),
                        Some(r) => Some(Some(per_chain[l].iter().position(|&x| x == r)?)),
                    }
                }
            };
            joints[l] = j as u32;
            let this = (*p as usize - start, kids, parent);
            match &shape {
                None => shape = Some(this),
                Some(first) if *first == this => {}
                Some(_) => return None,
            }
        }
        let (point, kids, parent) = shape?;
        out.push(LaneRotator {
            joints,
            point,
            kids,
            parent: match parent {
                None => RotatorParent::Root,
                Some(None) => RotatorParent::Joint(parents),
                Some(Some(k2)) if k2 < k => RotatorParent::Rotator(k2),
                Some(Some(_)) => return None,
            },
        });
    }
    Some(out)
}

/// What decides whether two chains step alike (twins have equal keys): the point tree
/// (parents relative to the chain's first point), the per-point parameters (bits), the
/// collider list, and the settings but for the names, the curves (already in the
/// per-point parameters), the dummy bone length (read only where the targets are
/// gathered) and the wind's seed (each lane has its own generator). The settings as
/// their `Debug` text: validated finite, so equal text is equal values (an `f32` prints
/// the shortest text that reads back to its bits; -0 and 0 print apart).
fn twin_key(rig: &ChainRig, ci: usize) -> (Vec<u32>, Vec<usize>, String) {
    let c = &rig.chains[ci];
    let mut points = Vec::with_capacity(c.points.len() * 7);
    for p in c.points.clone() {
        let parent = rig.parent[p];
        points.push(if parent == NONE {
            NONE
        } else {
            parent - c.points.start as u32
        });
        for v in [
            &rig.damping,
            &rig.stiffness,
            &rig.radius,
            &rig.wd_location,
            &rig.wd_rotation,
            &rig.limit_angle,
        ] {
            points.push(v[p].to_bits());
        }
    }
    let mut settings = c.settings.clone();
    settings.name.clear();
    settings.root.clear();
    settings.exclude.clear();
    settings.curves = Default::default();
    settings.dummy_bone_length = 0.0;
    settings.wind.seed = 0;
    (points, c.colliders.clone(), format!("{settings:?}"))
}

/// Chain `ci` of `rig` as a rig of one chain, its points from 0.
fn one_chain(rig: &ChainRig, ci: usize) -> ChainRig {
    let c = &rig.chains[ci];
    let range = c.points.clone();
    let slice = |v: &[f32]| v[range.clone()].to_vec();
    ChainRig {
        chains: vec![CompiledChain {
            settings: c.settings.clone(),
            points: 0..range.len(),
            colliders: c.colliders.clone(),
            base: c.base,
        }],
        colliders: rig.colliders.clone(),
        joint: rig.joint[range.clone()].to_vec(),
        parent: rig.parent[range.clone()]
            .iter()
            .map(|&p| {
                if p == NONE {
                    NONE
                } else {
                    p - range.start as u32
                }
            })
            .collect(),
        // Twin chains have no points between bones (`CompiledChain::scalar_only`).
        real_parent: rig.real_parent[range.clone()]
            .iter()
            .map(|&p| {
                if p == NONE {
                    NONE
                } else {
                    p - range.start as u32
                }
            })
            .collect(),
        inter_alpha: vec![0.0; range.len()],
        inter_end: vec![NONE; range.len()],
        carried: vec![false; range.len()],
        subdivided: false,
        chain_of: vec![0; range.len()],
        dummy_length: slice(&rig.dummy_length),
        damping: slice(&rig.damping),
        stiffness: slice(&rig.stiffness),
        radius: slice(&rig.radius),
        wd_location: slice(&rig.wd_location),
        wd_rotation: slice(&rig.wd_rotation),
        limit_angle: slice(&rig.limit_angle),
        rotators: Vec::new(),
        rotator_children: Vec::new(),
        constraints: Default::default(),
        syncs: Vec::new(),
        synced_chain: Vec::new(),
        length_rate: slice(&rig.length_rate),
        forces: Vec::new(),
        lane_groups: Vec::new(),
        scalar_rotators: Vec::new(),
        chain_in_lanes: Vec::new(),
        joint_count: rig.joint_count(),
        collider_groups: Vec::new(),
    }
}

/// A character's per-chain state in the scalar job's layout (all chains, all points),
/// for moving a group's chains into and out of their lanes.
pub(crate) struct ScalarChains<'a> {
    pub pos: &'a mut [Vec3],
    pub prev: &'a mut [Vec3],
    pub dev: &'a mut [Vec3],
    pub dev_before: &'a mut [Vec3],
    pub prev_targets: &'a mut [Vec3],
    pub prev_normals: &'a mut [Vec3],
    pub prev_colliders: &'a [PlacedCollider],
    pub last_step_component: &'a mut [Transform],
    pub accumulator: &'a mut [f32],
    pub dt_old: &'a mut [f32],
    pub rng: &'a mut [SplitMix64],
    pub needs_reset: &'a mut [bool],
    pub path: &'a CharacterPath,
    pub prev_component: Transform,
    pub teleports: &'a mut u64,
}

/// One lane group's state and working buffers.
#[derive(Debug, Clone)]
pub(crate) struct ChainLanes {
    twins: Twins,
}

impl ChainLanes {
    /// Fresh (unused) lanes for `group`: [`ChainLanes::load`] fills them.
    pub(crate) fn new(group: &ChainLaneGroup) -> Self {
        ChainLanes {
            twins: Twins::new(&group.rig, group.chains.len()),
        }
    }

    /// Whether these lanes were made for `group`.
    pub(crate) fn fits(&self, group: &ChainLaneGroup) -> bool {
        self.twins.fits(&group.rig, group.chains.len())
    }

    /// Takes the group's chains' state from the scalar layout.
    pub(crate) fn load(&mut self, rig: &ChainRig, group: &ChainLaneGroup, s: &mut ScalarChains) {
        for (l, &ci) in group.chains.iter().enumerate() {
            let start = rig.chains[ci].points.start;
            self.twins.load_lane(l, ci, start, s);
        }
    }

    /// Gives the group's chains' state back to the scalar layout (their resets counted
    /// there from now on).
    pub(crate) fn store(&mut self, rig: &ChainRig, group: &ChainLaneGroup, s: &mut ScalarChains) {
        for (l, &ci) in group.chains.iter().enumerate() {
            let start = rig.chains[ci].points.start;
            self.twins.store_lane(l, ci, start, s);
        }
    }

    /// Makes every chain of the group start again from its pose on the next frame.
    pub(crate) fn reset(&mut self) {
        self.twins.reset();
    }

    /// Resets (teleports, non-finite results) in the lanes since they were loaded.
    pub(crate) fn teleports(&self) -> u64 {
        self.twins.teleports()
    }

    /// The scalar job's `write_back` for the group's rotators (`group.write_back`), in
    /// lanes: each rotator joint turned toward its simulated children (mean direction) on
    /// top of its animated rotation. Runs before the scalar write-back of the others (no
    /// rotator of the group depends on another chain's).
    pub(crate) fn write_back(
        &self,
        group: &ChainLaneGroup,
        locals: &mut [Transform],
        models: &mut [Transform],
        turned: &mut Vec<TurnedRow>,
        isa: Isa,
    ) {
        let Some(rotators) = &group.write_back else {
            return;
        };
        // SAFETY (both): the function only requires the instructions of its lane type,
        // and `Isa::of` chose that type because the CPU has them.
        #[cfg(target_arch = "x86_64")]
        #[allow(unsafe_code)]
        match isa {
            Isa::Avx512 => {
                return unsafe { self.write_back_avx512(group, rotators, locals, models, turned) }
            }
            Isa::Avx2 => {
                return unsafe { self.write_back_avx2(group, rotators, locals, models, turned) }
            }
            Isa::Portable => {}
        }
        let _ = isa;
        self.write_back_lanes::<F>(group, rotators, locals, models, turned)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn write_back_avx2(
        &self,
        group: &ChainLaneGroup,
        rotators: &[LaneRotator],
        locals: &mut [Transform],
        models: &mut [Transform],
        turned: &mut Vec<TurnedRow>,
    ) {
        // The explicit AVX2 lane type, only here after the CPU was found to have AVX2.
        self.write_back_lanes::<crate::lanes::avx::Fa>(group, rotators, locals, models, turned)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
    fn write_back_avx512(
        &self,
        group: &ChainLaneGroup,
        rotators: &[LaneRotator],
        locals: &mut [Transform],
        models: &mut [Transform],
        turned: &mut Vec<TurnedRow>,
    ) {
        // The explicit AVX-512 lane type, only here after the CPU was found to have it.
        self.write_back_lanes::<crate::lanes::avx512::Fz>(group, rotators, locals, models, turned)
    }

    /// [`ChainLanes::write_back`] computed in the lane type `T`.
    #[inline(always)]
    fn write_back_lanes<T: Lane>(
        &self,
        group: &ChainLaneGroup,
        rotators: &[LaneRotator],
        locals: &mut [Transform],
        models: &mut [Transform],
        turned: &mut Vec<TurnedRow>,
    ) {
        let count = group.chains.len();
        // This frame's targets and output points, already in lanes.
        let (targets, out) = self.twins.targets_and_out();
        let zero = V3::<T>::splat(Vec3::ZERO);
        let tiny = T::splat(1e-12);
        // Two passes: first every row's new model rotation (the rows are independent, so
        // the processor overlaps their long chains of roots and divisions), then every
        // row's local rotation, which reads its parent row's. The same operations.
        turned.clear();
        for r in rotators {
            let (ta, oa) = (V3::<T>::of(targets[r.point]), V3::<T>::of(out[r.point]));
            let (mut anim, mut sim) = (zero, zero);
            for &c in &r.kids {
                anim = anim + (V3::<T>::of(targets[c]) - ta).normalize_or(zero);
                sim = sim + (V3::<T>::of(out[c]) - oa).normalize_or(zero);
            }
            let skip = anim.dot(anim).lt(tiny).or(sim.dot(sim).lt(tiny)).m();
            let mut animated = Q::splat(Quat::IDENTITY);
            for (l, &j) in r.joints.iter().enumerate().take(count) {
                animated.set(l, models[j as usize].rotation);
            }
            let new_rot = rotation_arc(anim, sim)
                .mul_quat(Q::<T>::of(animated))
                .normalize()
                .f();
            turned.push(TurnedRow {
                new_rot,
                turned: Q::select(skip, animated, new_rot),
                skip,
            });
        }
        for (r, row) in rotators.iter().zip(turned.iter()) {
            let parent_rot = match r.parent {
                RotatorParent::Rotator(k2) => turned[k2].turned,
                RotatorParent::Joint(q) => {
                    let mut p = Q::splat(Quat::IDENTITY);
                    for (l, &j) in q.iter().enumerate().take(count) {
                        p.set(l, models[j as usize].rotation);
                    }
                    p
                }
                RotatorParent::Root => Q::splat(Quat::IDENTITY),
            };
            let local = Q::<T>::of(parent_rot)
                .conjugate()
                .mul_quat(Q::<T>::of(row.new_rot))
                .normalize()
                .f();
            for (l, &j) in r.joints.iter().enumerate().take(count) {
                if row.skip.0[l] == 0 {
                    locals[j as usize].rotation = local.get(l);
                    models[j as usize].rotation = row.new_rot.get(l);
                }
            }
        }
    }

    /// One frame of the group's chains, as the scalar job's `run_chain` for each: reads
    /// the character's `targets`, `normals` (all points) and placed `colliders`, writes the
    /// group's chains' output points into `out`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn frame(
        &mut self,
        sk: &Skeleton,
        rig: &ChainRig,
        group: &ChainLaneGroup,
        frame: &LaneFrame,
        targets: &[Vec3],
        normals: &[Vec3],
        colliders: &[PlacedCollider],
        out: &mut [Vec3],
    ) {
        let starts = group.chains.iter().map(|&ci| rig.chains[ci].points.start);
        self.twins.frame(
            sk,
            &group.rig,
            &group.shapes,
            frame,
            starts,
            targets,
            normals,
            colliders,
            out,
        );
    }
}
/// The lanes of [`ChainLanes`]: a lane group whose "characters" are twin chains of
/// one character, run by the crowd's frame of one chain (`rig` is that chain as a rig of
/// its own).
#[derive(Debug, Clone)]
pub(crate) struct Twins {
    pub(crate) pack: Pack,
    pub(crate) scratch: Scratch,
}

impl Twins {
    /// Lanes for `count` twins of `rig`'s one chain.
    pub(crate) fn new(rig: &ChainRig, count: usize) -> Twins {
        let mut pack = Pack::new(rig);
        pack.count = count;
        pack.shared = true;
        Twins {
            pack,
            scratch: Scratch::new(rig, 0),
        }
    }

    /// Whether these lanes were made for `count` twins of `rig`'s one chain.
    pub(crate) fn fits(&self, rig: &ChainRig, count: usize) -> bool {
        self.pack.count == count
            && self.pack.pos.len() == rig.point_count()
            && self.scratch.colliders.len() == rig.colliders.len() * LANES
    }

    /// Lane `l` from chain `ci` (points from `start`) of the scalar state `s`.
    pub(crate) fn load_lane(&mut self, l: usize, ci: usize, start: usize, s: &mut ScalarChains) {
        let p = &mut self.pack;
        for k in 0..p.pos.len() {
            let q = start + k;
            p.pos[k].set(l, s.pos[q]);
            p.prev[k].set(l, s.prev[q]);
            p.dev[k].set(l, s.dev[q]);
            p.dev_before[k].set(l, s.dev_before[q]);
            p.prev_targets[k].set(l, s.prev_targets[q]);
            p.prev_normals[k].set(l, s.prev_normals[q]);
        }
        let (m, at) = (s.prev_colliders.len(), l * p.collider_stride());
        p.prev_colliders[at..at + m].copy_from_slice(s.prev_colliders);
        p.last_step_component[0].set(l, &s.last_step_component[ci]);
        p.accumulator[0].0[l] = s.accumulator[ci];
        p.dt_old[0].0[l] = s.dt_old[ci];
        p.rng[0][l] = s.rng[ci];
        p.needs_reset[0][l] = s.needs_reset[ci];
        p.paths[l] = *s.path;
        p.prev_component.set(l, &s.prev_component);
        p.teleports[l] = 0;
    }

    /// Lane `l` back into chain `ci` (points from `start`) of the scalar state `s`.
    pub(crate) fn store_lane(&mut self, l: usize, ci: usize, start: usize, s: &mut ScalarChains) {
        let p = &mut self.pack;
        for k in 0..p.pos.len() {
            let q = start + k;
            s.pos[q] = p.pos[k].get(l);
            s.prev[q] = p.prev[k].get(l);
            s.dev[q] = p.dev[k].get(l);
            s.dev_before[q] = p.dev_before[k].get(l);
            s.prev_targets[q] = p.prev_targets[k].get(l);
            s.prev_normals[q] = p.prev_normals[k].get(l);
        }
        s.last_step_component[ci] = p.last_step_component[0].get(l);
        s.accumulator[ci] = p.accumulator[0].0[l];
        s.dt_old[ci] = p.dt_old[0].0[l];
        s.rng[ci] = p.rng[0][l];
        s.needs_reset[ci] = p.needs_reset[0][l];
        *s.teleports += p.teleports[l];
        p.teleports[l] = 0;
    }

    /// The last frame's animated targets and output points, per point of the chain,
    /// lane by lane.
    pub(crate) fn targets_and_out(&self) -> (&[V3], &[V3]) {
        (&self.scratch.targets, &self.pack.out)
    }

    /// Every lane starts again from its pose on the next frame.
    pub(crate) fn reset(&mut self) {
        self.pack.needs_reset[0] = [true; LANES];
        // As the scalar state's reset: the character's path so far is forgotten.
        self.pack.paths = [CharacterPath::default(); LANES];
    }

    /// Resets in the lanes in use since they were loaded.
    pub(crate) fn teleports(&self) -> u64 {
        self.pack.teleports[..self.pack.count].iter().sum()
    }

    /// One frame: lane `l` reads the points of the chain starting at the `l`th of
    /// `starts` in `targets` and `normals`, every lane the same placed `colliders`; the
    /// lanes' output points are written back there into `out`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn frame(
        &mut self,
        sk: &Skeleton,
        rig: &ChainRig,
        shapes: &[LaneShape],
        frame: &LaneFrame,
        starts: impl Iterator<Item = usize> + Clone,
        targets: &[Vec3],
        normals: &[Vec3],
        colliders: &[PlacedCollider],
        out: &mut [Vec3],
    ) {
        let (pack, s) = (&mut self.pack, &mut self.scratch);
        let n = pack.pos.len();
        let m = colliders.len();
        // The normals only where a planar constraint reads them (`rig` is one chain).
        let planar = rig.planar_axis(0).is_some();
        for (l, start) in starts.clone().enumerate() {
            for k in 0..n {
                s.targets[k].set(l, targets[start + k]);
                if planar {
                    s.normals[k].set(l, normals[start + k]);
                }
            }
        }
        // The same colliders in every lane: kept once (`Pack::collider_stride`), and each
        // bound computed once.
        s.colliders[..m].copy_from_slice(colliders);
        for (b, c) in s.bounds.iter_mut().zip(colliders) {
            *b = Bound::splat(c);
        }
        s.component = Trs::splat(&frame.component);
        Ctx {
            sk,
            rig,
            shapes,
            planar: any_planar(rig),
            dt: frame.dt,
            isa: frame.isa,
        }
        .step(pack, s, false, None);
        for (l, start) in starts.enumerate() {
            for k in 0..n {
                out[start + k] = pack.out[k].get(l);
            }
        }
    }
}
