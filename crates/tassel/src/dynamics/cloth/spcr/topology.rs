//! SPCR's topology of a cloth: its points' values and its constraints in
//! `CreateConstraints`' order, its quads as `CreateSurfaceConstraints` makes them.

use crate::dynamics::cloth::settings::{ClothSettings, CollisionSwitches, ConstraintSwitches};
use std::ops::Range;

/// One SPCR constraint: its ends (global point indices), its strengths where it is
/// longer than at reset (SPCR's `Shrink`, Tassel's `stretch`) and shorter, and whether it
/// collides.
#[derive(Debug, Clone, Copy)]
pub(crate) struct SpcrConstraint {
    pub a: u32,
    pub b: u32,
    pub long: f64,
    pub short: f64,
    pub collide: bool,
}

/// A cloth's SPCR topology and per-point values, from the rig only.
#[derive(Debug, Clone, Default)]
pub(crate) struct SpcrRig {
    /// Per point (global index − the cloth's first point).
    pub weight: Vec<f64>,
    pub resist: Vec<f64>,
    pub gravity: Vec<f64>,
    pub hardness: Vec<f64>,
    /// SPCR's drag coefficient per metre of a step's displacement.
    pub drag: Vec<f64>,
    /// SPCR's lift, metres per step.
    pub lift: Vec<f64>,
    pub radius: Vec<f64>,
    pub friction: Vec<f64>,
    pub parent: Vec<Option<u32>>,
    pub child: Vec<Option<u32>>,
    pub constraints: Vec<SpcrConstraint>,
    /// SPCR's surface constraints `[A, B, BC, AC]` (global indices).
    pub quads: Vec<[u32; 4]>,
    pub first: usize,
    pub collision_lod: u32,
    pub sub_iterations: u32,
    pub limit_from_root: bool,
    pub wind_speed: f64,
}

impl SpcrRig {
    /// The SPCR topology of a cloth whose chains (global point ranges) are `chains`;
    /// `virtual_tip[p]` says a point is a virtual tip and `fixed[p]` that it follows the
    /// animation.
    pub(crate) fn build(
        s: &ClothSettings,
        chains: &[Range<usize>],
        virtual_tip: &[bool],
        fixed: &[bool],
    ) -> SpcrRig {
        let first = chains.first().map_or(0, |c| c.start);
        let last = chains.last().map_or(0, |c| c.end);
        let n = last - first;
        let h = f64::from(1.0f32 / s.step_rate);
        let mut r = SpcrRig {
            first,
            weight: vec![0.0; n],
            resist: vec![0.0; n],
            gravity: vec![0.0; n],
            hardness: vec![0.0; n],
            drag: vec![0.0; n],
            lift: vec![0.0; n],
            radius: vec![0.0; n],
            friction: vec![0.0; n],
            parent: vec![None; n],
            child: vec![None; n],
            collision_lod: s.collision_lod.unwrap_or(2),
            sub_iterations: s.collision_sub_iterations.unwrap_or(1),
            limit_from_root: s.limit_from_root.unwrap_or(false),
            wind_speed: f64::from(s.wind.speed.unwrap_or(1.0)),
            ..SpcrRig::default()
        };
        let mut order = vec![0.0f32; n];
        let c = &s.curves;
        for ch in chains {
            let has_tip = ch.clone().any(|p| virtual_tip[p]);
            let reals = ch.len() - usize::from(has_tip);
            for (k, p) in ch.clone().enumerate() {
                let i = p - first;
                // SPCR's `OrderRate`.
                order[i] = if virtual_tip[p] {
                    1.0
                } else {
                    let den = if has_tip {
                        reals
                    } else {
                        reals.saturating_sub(1)
                    };
                    if den == 0 {
                        0.0
                    } else {
                        k as f32 / den as f32
                    }
                };
                let x = order[i];
                r.weight[i] = if fixed[p] { 0.0 } else { 1.0 };
                let v = |x: f32| f64::from(x);
                r.resist[i] = 1.0 - v((s.resistance * c.resistance.eval(x)).clamp(0.0, 1.0));
                r.gravity[i] = v(s.gravity_scale * c.gravity_scale.eval(x));
                r.hardness[i] = v((s.hardness * c.hardness.eval(x)).clamp(0.0, 1.0));
                r.drag[i] = v((2.0 * s.drag * c.drag.eval(x)).clamp(0.0, 100.0));
                r.lift[i] = v(s.lift * c.lift.eval(x).clamp(0.0, 1.0)) * h * h;
                r.radius[i] = v((s.radius * c.radius.eval(x)).max(0.0));
                r.friction[i] = v((s.friction * c.friction.eval(x)).clamp(0.0, 1.0));
                r.parent[i] = (p > ch.start).then(|| (p - 1) as u32);
                r.child[i] = (p + 1 < ch.end).then(|| (p + 1) as u32);
            }
        }
        let sw: &ConstraintSwitches = &s.constraints;
        let col: CollisionSwitches = s.collision.unwrap_or_default();
        let pick = |curves: &crate::dynamics::cloth::StrengthCurves, kind: usize, x: f32| -> f64 {
            f64::from(match kind {
                0 => curves.structural_vertical.eval(x),
                1 => curves.structural_horizontal.eval(x),
                2 => curves.shear.eval(x),
                3 => curves.bending_vertical.eval(x),
                _ => curves.bending_horizontal.eval(x),
            })
        };
        let add = |out: &mut Vec<SpcrConstraint>, a: usize, b: usize, kind: usize, collide| {
            if fixed[a] && fixed[b] {
                return;
            }
            let x = (order[a - first] + order[b - first]) * 0.5;
            out.push(SpcrConstraint {
                a: a as u32,
                b: b as u32,
                long: pick(&s.stretch, kind, x),
                short: pick(&s.shrink, kind, x),
                collide,
            });
        };
        let count = chains.len();
        // Pairs of chains `gap` apart, as SPCR's `CreateConstraint…Horizontal` and
        // `…Shear` take them (wrapping with `bJointLoop`).
        let pairs = |gap: usize| -> Vec<(usize, usize)> {
            if count < 2 {
                Vec::new()
            } else if s.loop_chains {
                (0..count).map(|i| (i, (i + gap) % count)).collect()
            } else {
                (0..count.saturating_sub(gap))
                    .map(|i| (i, i + gap))
                    .collect()
            }
        };
        let at = |ch: &Range<usize>, k: usize| ch.start + k.min(ch.len() - 1);
        let mut cons = Vec::new();
        if sw.bending_horizontal {
            for (i, j) in pairs(2) {
                let (a, b) = (&chains[i], &chains[j]);
                for k in 0..a.len().max(b.len()) {
                    add(&mut cons, at(a, k), at(b, k), 4, false);
                }
            }
        }
        if sw.bending_vertical {
            for ch in chains {
                for k in 0..ch.len().saturating_sub(2) {
                    add(&mut cons, ch.start + k, ch.start + k + 2, 3, false);
                }
            }
        }
        if sw.shear {
            for (i, j) in pairs(1) {
                let (a, b) = (&chains[i], &chains[j]);
                let m = a.len().max(b.len());
                for k in 0..m {
                    add(&mut cons, at(a, k + 1), at(b, k), 2, col.shear);
                }
                for k in 0..m {
                    add(&mut cons, at(a, k), at(b, k + 1), 2, col.shear);
                }
            }
        }
        if sw.structural_horizontal {
            for (i, j) in pairs(1) {
                let (a, b) = (&chains[i], &chains[j]);
                for k in 0..a.len().max(b.len()) {
                    add(&mut cons, at(a, k), at(b, k), 1, col.structural_horizontal);
                }
            }
        }
        if sw.structural_vertical {
            for _ in 0..s.structural_vertical_step_count.unwrap_or(1) {
                for ch in chains {
                    for k in 0..ch.len().saturating_sub(1) {
                        add(
                            &mut cons,
                            ch.start + k,
                            ch.start + k + 1,
                            0,
                            col.structural_vertical,
                        );
                    }
                }
            }
        }
        r.constraints = cons;
        // `CreateSurfaceConstraints`: neighbouring chains, never wrapping.
        for i in 0..count.saturating_sub(1) {
            let (a, b) = (&chains[i], &chains[i + 1]);
            for k in 0..a.len().max(b.len()) {
                let q = [at(a, k), at(b, k), at(b, k + 1), at(a, k + 1)];
                if q.iter().any(|&p| !fixed[p]) {
                    r.quads.push(q.map(|p| p as u32));
                }
            }
        }
        r
    }
}
