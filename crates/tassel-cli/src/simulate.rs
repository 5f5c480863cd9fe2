//! `tassel simulate`: the scripted, machine-readable run (contract in README.md).

use crate::output::{write_atomic_with, JsonStream};
use crate::subject::{read_rig, Mode};
use glam::{Quat, Vec3};
use serde_json::json;
use std::path::PathBuf;
use tassel::dynamics::SimMode;
use tassel::{builtin, CharacterSim, Transform};

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Motion {
    None,
    Sin,
    Step,
    Linear,
    Rotate,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Axis {
    X,
    Y,
    Z,
}

/// Options of `tassel simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// The model (.glb, .gltf, .vrm); omit with --builtin.
    model: Option<PathBuf>,
    /// Rig file (TOML) with chains and colliders; with --builtin it replaces the built-in
    /// rig; optional for a VRM (its spring bones run in any case).
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Use the embedded character.
    #[arg(long)]
    builtin: bool,
    /// fixed (default for VRM): VRM springs and chains at a fixed rate, the same look at
    /// every frame rate; spec: VRM springs by the specification; classic: chains frame by
    /// frame (VRM springs spec); three-vrm: as three-vrm 3.5.5. Default for a rig: what the
    /// rig says.
    #[arg(long, value_enum)]
    mode: Option<Mode>,
    /// Number of frames.
    #[arg(long, default_value_t = 60)]
    frames: usize,
    /// Frame time, seconds.
    #[arg(long, default_value_t = 1.0 / 60.0)]
    dt: f32,
    /// Motion of the scene root.
    #[arg(long, value_enum, default_value = "none")]
    motion: Motion,
    /// Amplitude: metres (sin, step), metres per second (linear), radians (rotate).
    #[arg(long, default_value_t = 0.5)]
    amp: f32,
    /// Frequency, Hz (sin, rotate).
    #[arg(long, default_value_t = 1.0)]
    freq: f32,
    /// Axis of translation motions.
    #[arg(long, value_enum, default_value = "x")]
    axis: Axis,
    /// Output JSON file.
    #[arg(long)]
    out: PathBuf,
}

fn root_motion(a: &Args, t: f32) -> Transform {
    let axis = match a.axis {
        Axis::X => Vec3::X,
        Axis::Y => Vec3::Y,
        Axis::Z => Vec3::Z,
    };
    let w = std::f32::consts::TAU * a.freq * t;
    match a.motion {
        Motion::None => Transform::IDENTITY,
        Motion::Sin => Transform::from_translation(axis * a.amp * w.sin()),
        Motion::Step => Transform::from_translation(axis * a.amp),
        Motion::Linear => Transform::from_translation(axis * a.amp * t),
        Motion::Rotate => {
            Transform::from_translation_rotation(Vec3::ZERO, Quat::from_rotation_y(a.amp * w.sin()))
        }
    }
}

/// What a listed joint's tail is.
#[derive(Clone, Copy)]
enum Tail {
    /// A joint of the skeleton.
    Joint(usize),
    /// A point in the joint's own space (a VRM virtual tail).
    Local(glam::Vec3),
    /// A virtual chain point (model space, from the chain state).
    ChainPoint(usize),
    /// A virtual cloth tip (world space, from the cloth state) and the virtual bone's
    /// length: the written bone's tip, toward that point.
    ClothPoint(usize, f32),
    /// None: the joint itself (a spring bone without children).
    Own,
}

pub fn run(a: Args) -> Result<(), String> {
    if !(a.dt.is_finite() && a.dt > 0.0 && a.dt <= 1.0) {
        return Err(format!(
            "--dt {} must be a number of seconds in (0, 1]",
            a.dt
        ));
    }
    if a.frames == 0 || a.frames > 1_000_000 {
        return Err(format!("--frames {} must be 1..=1000000", a.frames));
    }
    for (name, v) in [("--amp", a.amp), ("--freq", a.freq)] {
        if !v.is_finite() {
            return Err(format!("{name} {v} is not a finite number"));
        }
    }
    let (skeleton, mut rig, joint_to_node, vrm) = match (&a.model, a.builtin) {
        (Some(_), true) => return Err("give either MODEL or --builtin, not both".into()),
        (None, false) => return Err("give a MODEL file or --builtin".into()),
        (None, true) => {
            let c = builtin::character();
            let rig = match &a.rig {
                Some(p) => read_rig(p)?,
                None => c.rig,
            };
            let n = c.skeleton.len();
            (c.skeleton, rig, (0..n).collect::<Vec<_>>(), None)
        }
        (Some(path), false) => {
            let model = tassel_gltf::load(path).map_err(|e| e.to_string())?;
            let vrm = model.vrm.map(|v| v.springs);
            let rig = crate::subject::rig_or_vrm(a.rig.as_ref(), vrm.is_some(), path)?;
            (model.skeleton, rig, model.joint_to_node, vrm)
        }
    };
    let vrm = vrm.unwrap_or_default();
    let (mode, options) = SimMode::apply(a.mode.map(Mode::into), &mut rig, !vrm.is_empty())
        .map_err(|e| format!("--mode: {e}"))?;
    let mode_name = mode.name();
    let mut sim =
        CharacterSim::with_vrm(skeleton.clone(), &rig, &vrm, options).map_err(|e| e.to_string())?;
    let mut joints: Vec<(usize, Tail)> = sim
        .vrm()
        .links
        .iter()
        .map(|l| {
            (
                l.joint,
                match l.tail_joint {
                    Some(t) => Tail::Joint(t),
                    None => Tail::Local(l.tail_local),
                },
            )
        })
        .collect();
    joints.extend(sim.chains().rotating_joints().map(|(j, _, tail)| {
        (
            j,
            match sim.chains().point(tail).joint {
                Some(tj) => Tail::Joint(tj),
                None => Tail::ChainPoint(tail),
            },
        )
    }));
    // Springs: the bone (its first child as the tail).
    for i in 0..sim.springs().len() {
        let j = sim.springs().joint(i);
        let child = (j + 1..skeleton.len()).find(|&c| skeleton.parent(c) == Some(j));
        joints.push((j, child.map_or(Tail::Own, Tail::Joint)));
    }
    // Cloths: every joint that turns toward a free point of its chain, that point as the
    // tail (a bone, or the chain's virtual tip).
    let cloths = sim.cloths();
    for ci in 0..cloths.cloth_count() {
        let tip = cloths.settings(ci).virtual_bone_length;
        for chain in cloths.chains(ci) {
            for p in chain.start..chain.end.saturating_sub(1) {
                let next = p + 1;
                if let (Some(j), false) = (cloths.joint(p), cloths.is_fixed(next)) {
                    joints.push((
                        j,
                        cloths
                            .joint(next)
                            .map_or(Tail::ClothPoint(next, tip), Tail::Joint),
                    ));
                }
            }
        }
    }
    // Ropes: each bone but the last turns toward the next.
    for ri in 0..sim.ropes().len() {
        for pair in sim.ropes().bones(ri).windows(2) {
            joints.push((pair[0], Tail::Joint(pair[1])));
        }
    }
    let rest = skeleton.rest().to_vec();
    let world = |sim: &CharacterSim, comp: &Transform| {
        let models = &sim.pose().models;
        let mut pos = Vec::with_capacity(joints.len());
        let mut tails = Vec::with_capacity(joints.len());
        let mut quats = Vec::with_capacity(joints.len());
        for &(j, tail) in &joints {
            let w = *comp * models[j];
            pos.push(w.translation.to_array());
            let tail_pos = match tail {
                Tail::Joint(t) => comp.transform_point(models[t].translation),
                Tail::Local(p) => w.transform_point(p),
                Tail::ChainPoint(p) => {
                    comp.transform_point(sim.chain_state().output_positions()[p])
                }
                Tail::ClothPoint(p, length) => {
                    let toward = sim.cloth_state().world_positions()[p] - w.translation;
                    w.translation + toward.normalize_or_zero() * length
                }
                Tail::Own => w.translation,
            };
            tails.push(tail_pos.to_array());
            quats.push(w.rotation.normalize().to_array());
        }
        (pos, tails, quats)
    };
    // The rest state before frame 1: a zero-length frame initialises every solver there.
    sim.frame(&rest, Transform::IDENTITY, 0.0)
        .map_err(|e| e.to_string())?;
    let (initial_pos, initial_tails, _) = world(&sim, &Transform::IDENTITY);
    let joint_list: Vec<_> = joints
        .iter()
        .map(|&(j, tail)| {
            json!({
                "node": joint_to_node[j],
                "name": skeleton.name(j),
                "tail_node": match tail { Tail::Joint(t) => Some(joint_to_node[t]), _ => None },
            })
        })
        .collect();
    let head = json!({
        "dt": a.dt, "frames": a.frames, "mode": mode_name, "joints": joint_list,
        "initial": { "world_pos": initial_pos, "tail_world_pos": initial_tails },
    });
    // Streamed frame by frame: a million frames never sit in memory.
    write_atomic_with(&a.out, |out| {
        let mut doc = JsonStream::begin(out, &head, "samples")?;
        for f in 1..=a.frames {
            let t = f as f32 * a.dt;
            let comp = root_motion(&a, t);
            sim.frame(&rest, comp, a.dt)
                .map_err(|e| format!("frame {f}: {e}"))?;
            let (pos, tails, quats) = world(&sim, &comp);
            let sample = json!({
                "frame": f, "t": t, "root_pos": comp.translation.to_array(),
                "world_pos": pos, "tail_world_pos": tails, "world_quat": quats,
            });
            doc.push(&sample, &format!("frame {f}"))?;
        }
        doc.end()
    })?;
    say!(
        "wrote {} ({} joints, {} frames, mode {mode_name})",
        a.out.display(),
        joints.len(),
        a.frames
    );
    Ok(())
}
