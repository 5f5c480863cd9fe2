//! Scaffolding shared by the core's scenario tests (each test file uses part of it).
#![allow(dead_code)]

use glam::{DQuat, DVec3, Quat, Vec3};
use std::sync::Arc;
use tassel::controller::{Level, LevelCollider, LevelShape};
use tassel::{Skeleton, Transform};

/// An anchor joint at `anchor` and `n` bones `b0..` of `len` along `dir`.
pub fn line(n: usize, len: f32, dir: Vec3, anchor: Vec3) -> Skeleton {
    let mut names = vec!["anchor".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::from_translation(anchor)];
    for i in 0..n {
        names.push(format!("b{i}"));
        parents.push(Some(i));
        rest.push(Transform::from_translation(dir * len));
    }
    Skeleton::new(names, parents, rest).unwrap()
}

/// A level box centred at `centre`.
pub fn boxed(name: &str, centre: Vec3, half: Vec3) -> LevelCollider {
    LevelCollider::new(name, LevelShape::Box { half_extents: half }, centre)
}

/// A floor: the top of a 100 m box at y = 0.
pub fn floor() -> Arc<Level> {
    let floor = boxed(
        "floor",
        Vec3::new(0.0, -0.5, 0.0),
        Vec3::new(50.0, 0.5, 50.0),
    );
    Arc::new(Level::new(vec![floor]).unwrap())
}

/// A 5 cm wall across +Z whose near face is at z = `near`.
pub fn thin_wall(near: f32) -> Arc<Level> {
    let wall = boxed(
        "wall",
        Vec3::new(0.0, 0.0, near + 0.025),
        Vec3::new(2.0, 2.0, 0.025),
    );
    Arc::new(Level::new(vec![wall]).unwrap())
}

/// A character walking along +Z at 2 m/s, turning 0.8 rad from 1.5 s to 2.5 s and
/// stopping at 3 s.
pub fn drag_walk(t: f32) -> Transform {
    let yaw = if t > 1.5 {
        0.8 * (t - 1.5).min(1.0)
    } else {
        0.0
    };
    Transform::from_translation_rotation(
        Vec3::new(0.0, 0.0, 2.0 * t.min(3.0)),
        Quat::from_rotation_y(yaw),
    )
}

/// A character running along +Z at 10 m/s for 0.1 s, then standing.
pub fn flung(t: f32) -> Transform {
    Transform::from_translation(Vec3::new(0.0, 0.0, 10.0 * t.min(0.1)))
}

/// The 6-bone hair chain of the KawaiiPhysics reference tests.
pub mod hair {
    use super::*;

    /// Simulated bones below the root.
    pub const BONES: usize = 6;

    /// Head at 1.6 m; hair from the back of the head, down and back (component space).
    pub fn pose() -> Vec<DVec3> {
        let mut p = vec![DVec3::new(0.0, 1.62, -0.1)];
        for i in 0..BONES {
            let last = p[i];
            p.push(last + DVec3::new(0.004 * i as f64, -0.06, -0.015));
        }
        p
    }

    /// `hair_0..=hair_6` on that pose.
    pub fn skeleton() -> Skeleton {
        let p = pose();
        let mut names = vec!["hair_0".to_string()];
        let mut parents = vec![None];
        let mut rest = vec![Transform::from_translation(p[0].as_vec3())];
        for i in 1..=BONES {
            names.push(format!("hair_{i}"));
            parents.push(Some(i - 1));
            rest.push(Transform::from_translation((p[i] - p[i - 1]).as_vec3()));
        }
        Skeleton::new(names, parents, rest).unwrap()
    }

    /// The component (character) transform at `t`, f64: still, swaying ±0.3 m at 1 Hz,
    /// stepped 0.2 m at 0.5 s, or turning ±0.5 rad at 0.7 Hz.
    pub fn component(motion: &str, t: f64) -> (DVec3, DQuat) {
        match motion {
            "still" => (DVec3::ZERO, DQuat::IDENTITY),
            "sway" => (
                DVec3::new(0.3 * (std::f64::consts::TAU * t).sin(), 0.0, 0.0),
                DQuat::IDENTITY,
            ),
            "step" => (
                DVec3::new(if t >= 0.5 { 0.2 } else { 0.0 }, 0.0, 0.0),
                DQuat::IDENTITY,
            ),
            "turn" => (
                DVec3::ZERO,
                DQuat::from_rotation_y(0.5 * (std::f64::consts::TAU * 0.7 * t).sin()),
            ),
            _ => unreachable!(),
        }
    }
}
