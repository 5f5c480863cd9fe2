//! A lane group's chain state ([`Pack`]: up to [`LANES`] lanes, one chain of the rig per
//! lane and point) and one thread's working buffers for a frame ([`Scratch`]).

use super::frame::MotionMemo;
use super::step::Ahead;
use crate::collide::lanes::Bound;
use crate::collide::PlacedCollider;
use crate::dynamics::chain::compile::ChainRig;
use crate::dynamics::chain::job::chain_rng;
use crate::dynamics::path::CharacterPath;
use crate::error::Error;
use crate::lanes::{Trs, F, LANES, M, Q, V3};
use crate::math::Transform;
use crate::rng::SplitMix64;
use glam::{Quat, Vec3};

/// A lane group: the chain state of up to [`LANES`] characters, one per lane.
#[derive(Debug, Clone)]
pub(crate) struct Pack {
    /// Characters in use (the other lanes are computed, unseen, and never collide).
    pub(crate) count: usize,
    // Per point.
    pub(crate) pos: Vec<V3>,
    pub(crate) prev: Vec<V3>,
    pub(crate) dev: Vec<V3>,
    pub(crate) dev_before: Vec<V3>,
    pub(crate) out: Vec<V3>,
    pub(crate) prev_targets: Vec<V3>,
    pub(crate) prev_normals: Vec<V3>,
    /// Last frame's placed colliders, lane after lane (`m` per lane; `shared`: the first
    /// lane's only, [`Pack::collider_stride`]).
    pub(crate) prev_colliders: Vec<PlacedCollider>,
    // Per chain.
    pub(crate) last_step_component: Vec<Trs>,
    pub(crate) accumulator: Vec<F>,
    pub(crate) dt_old: Vec<F>,
    pub(crate) rng: Vec<[SplitMix64; LANES]>,
    pub(crate) needs_reset: Vec<[bool; LANES]>,
    // Per lane.
    pub(crate) paths: [CharacterPath; LANES],
    pub(crate) prev_component: Trs,
    pub(crate) teleports: [u64; LANES],
    /// The local rotation each rotator joint got (per rotator).
    pub(crate) out_rotation: Vec<Q>,
    /// The characters (crowd indices) whose input was bad in the last frame, and why:
    /// their lanes were held (their state as before the frame).
    pub(crate) held: Vec<(usize, Error)>,
    /// Every lane is the same character (twin chains of one character: one path, one
    /// transform, the same colliders): a lane's place on the path, placed colliders and
    /// motion are copied from an earlier lane that asked the same, not computed again;
    /// the frame's placed colliders are kept once, in the first lane's place.
    pub(crate) shared: bool,
}

impl Pack {
    /// How far apart two neighbouring lanes' placed colliders are in `prev_colliders`
    /// and in the scratch's `colliders` (lane `l`'s start at `l` times it): `m`, or 0
    /// where every lane has the same (`shared`).
    pub(crate) fn collider_stride(&self) -> usize {
        if self.shared {
            0
        } else {
            self.prev_colliders.len() / LANES
        }
    }

    pub(crate) fn new(rig: &ChainRig) -> Pack {
        let n = rig.point_count();
        let m = rig.colliders.len();
        let c = rig.chains.len();
        let zero = V3::splat(Vec3::ZERO);
        let y = V3::splat(Vec3::Y);
        let id = Trs::splat(&Transform::IDENTITY);
        Pack {
            count: 0,
            pos: vec![zero; n],
            prev: vec![zero; n],
            dev: vec![zero; n],
            dev_before: vec![zero; n],
            out: vec![zero; n],
            prev_targets: vec![zero; n],
            prev_normals: vec![y; n],
            prev_colliders: vec![placeholder(); m * LANES],
            last_step_component: vec![id; c],
            accumulator: vec![F::splat(0.0); c],
            dt_old: vec![F::splat(0.0); c],
            rng: (0..c).map(|ci| [chain_rng(rig, ci); LANES]).collect(),
            needs_reset: vec![[true; LANES]; c],
            paths: [CharacterPath::default(); LANES],
            prev_component: id,
            teleports: [0; LANES],
            out_rotation: vec![Q::splat(Quat::IDENTITY); rig.rotators.len()],
            held: Vec::new(),
            shared: false,
        }
    }

    /// Lane `l` as a fresh character (the first frame starts it from its pose).
    pub(crate) fn clear_lane(&mut self, rig: &ChainRig, l: usize) {
        for (ci, r) in self.rng.iter_mut().enumerate() {
            r[l] = chain_rng(rig, ci);
        }
        for n in &mut self.needs_reset {
            n[l] = true;
        }
        self.paths[l] = CharacterPath::default();
        self.prev_component.set(l, &Transform::IDENTITY);
        self.teleports[l] = 0;
    }
}

pub(crate) fn placeholder() -> PlacedCollider {
    PlacedCollider {
        shape: crate::collide::Shape::Plane,
        transform: Transform::IDENTITY,
    }
}

/// One character's state, taken out of its lane (to move it to another).
#[derive(Debug, Clone)]
pub(crate) struct LaneState {
    pub(crate) points: [Vec<Vec3>; 7],
    pub(crate) prev_colliders: Vec<PlacedCollider>,
    pub(crate) last_step_component: Vec<Transform>,
    pub(crate) accumulator: Vec<f32>,
    pub(crate) dt_old: Vec<f32>,
    pub(crate) rng: Vec<SplitMix64>,
    pub(crate) needs_reset: Vec<bool>,
    pub(crate) path: CharacterPath,
    pub(crate) prev_component: Transform,
    pub(crate) teleports: u64,
    pub(crate) out_rotation: Vec<Quat>,
}

impl Pack {
    pub(crate) fn point_fields(&mut self) -> [&mut Vec<V3>; 7] {
        [
            &mut self.pos,
            &mut self.prev,
            &mut self.dev,
            &mut self.dev_before,
            &mut self.out,
            &mut self.prev_targets,
            &mut self.prev_normals,
        ]
    }

    /// This group's per-point state, as the group before it asks it into the caches while
    /// it steps ([`Ahead`]): [`Pack::point_fields`] but `prev_normals`, which only a
    /// chain with a planar constraint reads.
    pub(crate) fn ahead(&self) -> Ahead<'_> {
        [
            &self.pos,
            &self.prev,
            &self.dev,
            &self.dev_before,
            &self.out,
            &self.prev_targets,
        ]
    }

    /// Asks this group's per-chain and per-lane state into the second-level cache; called
    /// while the group before it runs its frame (its per-point state that group's step
    /// asks point by point, [`Ahead`], and its rotations that group's write-back asks
    /// rotator by rotator). A crowd larger than the caches otherwise waits for each piece
    /// where it is first read (`tassel bench --crowd 10000`). A hint only: no effect on
    /// any value.
    pub(crate) fn prefetch_frame_state(&self) {
        use crate::lanes::prefetch;
        prefetch(&self.accumulator[..]);
        prefetch(&self.dt_old[..]);
        prefetch(&self.needs_reset[..]);
        prefetch(&self.last_step_component[..]);
        prefetch(&self.rng[..]);
        prefetch(&self.paths[..]);
        prefetch(std::slice::from_ref(&self.prev_component));
        prefetch(&self.teleports[..]);
        prefetch(&self.prev_colliders[..]);
    }

    pub(crate) fn lane(&mut self, l: usize) -> LaneState {
        let m = self.prev_colliders.len() / LANES;
        LaneState {
            points: self
                .point_fields()
                .map(|f| f.iter().map(|v| v.get(l)).collect()),
            prev_colliders: self.prev_colliders[l * m..(l + 1) * m].to_vec(),
            last_step_component: self.last_step_component.iter().map(|t| t.get(l)).collect(),
            accumulator: self.accumulator.iter().map(|a| a.get(l)).collect(),
            dt_old: self.dt_old.iter().map(|a| a.get(l)).collect(),
            rng: self.rng.iter().map(|r| r[l]).collect(),
            needs_reset: self.needs_reset.iter().map(|r| r[l]).collect(),
            path: self.paths[l],
            prev_component: self.prev_component.get(l),
            teleports: self.teleports[l],
            out_rotation: self.out_rotation.iter().map(|q| q.get(l)).collect(),
        }
    }

    pub(crate) fn set_lane(&mut self, l: usize, s: &LaneState) {
        for (field, values) in self.point_fields().into_iter().zip(&s.points) {
            for (d, v) in field.iter_mut().zip(values) {
                d.set(l, *v);
            }
        }
        let m = self.prev_colliders.len() / LANES;
        self.prev_colliders[l * m..(l + 1) * m].copy_from_slice(&s.prev_colliders);
        for (d, t) in self
            .last_step_component
            .iter_mut()
            .zip(&s.last_step_component)
        {
            d.set(l, t);
        }
        for (d, v) in self.accumulator.iter_mut().zip(&s.accumulator) {
            d.0[l] = *v;
        }
        for (d, v) in self.dt_old.iter_mut().zip(&s.dt_old) {
            d.0[l] = *v;
        }
        for (d, v) in self.rng.iter_mut().zip(&s.rng) {
            d[l] = *v;
        }
        for (d, v) in self.needs_reset.iter_mut().zip(&s.needs_reset) {
            d[l] = *v;
        }
        self.paths[l] = s.path;
        self.prev_component.set(l, &s.prev_component);
        self.teleports[l] = s.teleports;
        for (d, q) in self.out_rotation.iter_mut().zip(&s.out_rotation) {
            d.set(l, *q);
        }
    }
}

/// One thread's working buffers: a frame's input and a step's interpolated input.
#[derive(Debug, Clone)]
pub(crate) struct Scratch {
    /// Per lane (`n` joints each): the animated models of the colliders' bones (the
    /// other joints' are not kept).
    pub(crate) models: Vec<Transform>,
    /// The model pose per joint, all lanes side by side (computed in lanes).
    pub(crate) lane_models: Vec<Trs>,
    /// The animated local rotation per joint, all lanes side by side.
    pub(crate) lane_local_rotations: Vec<Q>,
    pub(crate) component: Trs,
    /// This frame's animated targets and planar normals per point (a normal only for the
    /// points of chains with a planar constraint: no other step reads one), colliders
    /// lane after lane, and the colliders' broad-phase spheres.
    pub(crate) targets: Vec<V3>,
    pub(crate) normals: Vec<V3>,
    pub(crate) colliders: Vec<PlacedCollider>,
    pub(crate) bounds: Vec<Bound>,
    /// A step's: targets, normals, colliders, spheres, and the share of the frame each
    /// collider (per lane) was placed at (bits; NaN: not this frame's).
    pub(crate) step_targets: Vec<V3>,
    pub(crate) step_normals: Vec<V3>,
    pub(crate) step_colliders: Vec<PlacedCollider>,
    pub(crate) step_bounds: Vec<Bound>,
    pub(crate) step_placed_at: Vec<f32>,
    /// Each lane's place on its path at the share `path_w` of the frame (bits; NaN: not
    /// this frame's): the chains of a character mostly step at the same shares.
    pub(crate) path_w: [f32; LANES],
    pub(crate) path_at: Trs,
    /// The write-back's model rotations per joint (the rotator joints and their parents).
    pub(crate) rotations: Vec<Q>,
    /// The write-back's new model rotation per rotator, and the lanes it leaves animated.
    pub(crate) new_rotations: Vec<(Q, M)>,
    /// A point's broad phase: the lanes each member of its chain's collider list may touch.
    pub(crate) near: Vec<M>,
    /// The previous positions fixed mode's output step moves (not the kept ones).
    pub(crate) keep_prev: Vec<V3>,
    /// The last motion computed.
    pub(crate) motion: MotionMemo,
    /// Each lane's motion since the last frame: how far it moved and how far it turned
    /// (degrees), for every chain's teleport test.
    pub(crate) jump: [(f32, f32); LANES],
}

impl Scratch {
    pub(crate) fn new(rig: &ChainRig, joints: usize) -> Scratch {
        let n = rig.point_count();
        let m = rig.colliders.len();
        let zero = V3::splat(Vec3::ZERO);
        Scratch {
            models: vec![Transform::IDENTITY; joints * LANES],
            lane_models: vec![Trs::splat(&Transform::IDENTITY); joints],
            lane_local_rotations: vec![Q::splat(Quat::IDENTITY); joints],
            component: Trs::splat(&Transform::IDENTITY),
            targets: vec![zero; n],
            normals: vec![V3::splat(Vec3::Y); n],
            colliders: vec![placeholder(); m * LANES],
            bounds: vec![Bound::ZERO; m],
            step_targets: vec![zero; n],
            step_normals: vec![V3::splat(Vec3::Y); n],
            step_colliders: vec![placeholder(); m * LANES],
            step_bounds: vec![Bound::ZERO; m],
            step_placed_at: vec![f32::NAN; m * LANES],
            path_w: [f32::NAN; LANES],
            path_at: Trs::splat(&Transform::IDENTITY),
            rotations: vec![Q::splat(Quat::IDENTITY); joints],
            new_rotations: vec![(Q::splat(Quat::IDENTITY), M::NONE); rig.rotators.len()],
            near: vec![
                M::ALL;
                rig.chains
                    .iter()
                    .map(|c| c.colliders.len())
                    .max()
                    .unwrap_or(0)
            ],
            keep_prev: vec![zero; n],
            motion: MotionMemo::new(),
            jump: [(0.0, 0.0); LANES],
        }
    }
}
