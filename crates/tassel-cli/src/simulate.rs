//! `tassel simulate`: the scripted, machine-readable run (contract in README.md).

use crate::output::write_atomic;
use glam::{Quat, Vec3};
use serde_json::json;
use std::path::PathBuf;
use tassel::dynamics::chain::TimeMode;
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Pose, Skeleton, Transform};

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Mode {
    Spec,
    Fixed,
    Classic,
}

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
    /// The model (.glb, .gltf); omit with --builtin.
    model: Option<PathBuf>,
    /// Rig file (TOML) with chains and colliders; with --builtin it replaces the built-in rig.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// Use the embedded character.
    #[arg(long)]
    builtin: bool,
    /// Time mode for every chain (default: what the rig says).
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

fn read_rig(path: &PathBuf) -> Result<RigSettings, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    RigSettings::from_toml_str(&text).map_err(|e| format!("{}: {e}", path.display()))
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
    let (skeleton, mut rig, joint_to_node): (Skeleton, RigSettings, Vec<usize>) =
        match (&a.model, a.builtin) {
            (Some(_), true) => return Err("give either MODEL or --builtin, not both".into()),
            (None, false) => return Err("give a MODEL file or --builtin".into()),
            (None, true) => {
                let c = builtin::character();
                let rig = match &a.rig {
                    Some(p) => read_rig(p)?,
                    None => c.rig,
                };
                let n = c.skeleton.len();
                (c.skeleton, rig, (0..n).collect())
            }
            (Some(path), false) => {
                let model = tassel_gltf::load(path).map_err(|e| e.to_string())?;
                let rig = match &a.rig {
                    Some(p) => read_rig(p)?,
                    None => {
                        return Err(format!(
                            "{}: give --rig RIG.toml (VRM spring bones are not supported yet)",
                            path.display()
                        ))
                    }
                };
                (model.skeleton, rig, model.joint_to_node)
            }
        };
    let mode_name = match a.mode {
        Some(Mode::Spec) => return Err("--mode spec is the VRM spring-bone mode, which is not supported yet; use fixed or classic".into()),
        Some(Mode::Fixed) => "fixed",
        Some(Mode::Classic) => "classic",
        None => match rig.chains.first().map(|c| c.mode) {
            Some(TimeMode::Classic) => "classic",
            _ => "fixed",
        },
    };
    if let Some(m) = a.mode {
        for c in &mut rig.chains {
            c.mode = if m == Mode::Classic {
                TimeMode::Classic
            } else {
                TimeMode::Fixed
            };
        }
    }
    let mut sim = CharacterSim::new(skeleton.clone(), &rig).map_err(|e| e.to_string())?;
    let joints: Vec<(usize, usize, usize)> = sim.chains().rotating_joints().collect();
    let rest = skeleton.rest().to_vec();
    let world = |pose: &Pose, sim: &CharacterSim, comp: &Transform| {
        let mut pos = Vec::new();
        let mut tails = Vec::new();
        let mut quats = Vec::new();
        for &(j, _, tail) in &joints {
            pos.push(comp.transform_point(pose.models[j].translation).to_array());
            let tail_pos = match sim.chains().point(tail).joint {
                Some(tj) => pose.models[tj].translation,
                None => sim.state().output_positions()[tail],
            };
            tails.push(comp.transform_point(tail_pos).to_array());
            quats.push(
                (comp.rotation * pose.models[j].rotation)
                    .normalize()
                    .to_array(),
            );
        }
        (pos, tails, quats)
    };
    let rest_pose = Pose::rest(&skeleton);
    let initial_tails: Vec<[f32; 3]> = joints
        .iter()
        .map(|&(_, _, tail)| match sim.chains().point(tail).joint {
            Some(tj) => rest_pose.models[tj].translation.to_array(),
            None => Vec3::ZERO.to_array(),
        })
        .collect();
    // Settle the state at rest before frame 1 (a zero-length frame).
    sim.frame(&rest, Transform::IDENTITY, 0.0)
        .map_err(|e| e.to_string())?;
    let (initial_pos, virtual_tails, _) = world(&rest_pose, &sim, &Transform::IDENTITY);
    let initial_tails: Vec<[f32; 3]> = initial_tails
        .iter()
        .zip(&virtual_tails)
        .zip(&joints)
        .map(|((r, v), &(_, _, tail))| {
            if sim.chains().point(tail).joint.is_some() {
                *r
            } else {
                *v
            }
        })
        .collect();
    let mut samples = Vec::with_capacity(a.frames);
    for f in 1..=a.frames {
        let t = f as f32 * a.dt;
        let comp = root_motion(&a, t);
        let pose = sim
            .frame(&rest, comp, a.dt)
            .map_err(|e| e.to_string())?
            .clone();
        let (pos, tails, quats) = world(&pose, &sim, &comp);
        samples.push(json!({
            "frame": f, "t": t, "root_pos": comp.translation.to_array(),
            "world_pos": pos, "tail_world_pos": tails, "world_quat": quats,
        }));
    }
    let joint_list: Vec<_> = joints
        .iter()
        .map(|&(j, _, tail)| {
            json!({
                "node": joint_to_node[j],
                "name": skeleton.name(j),
                "tail_node": sim.chains().point(tail).joint.map(|tj| joint_to_node[tj]),
            })
        })
        .collect();
    let doc = json!({
        "dt": a.dt, "frames": a.frames, "mode": mode_name, "joints": joint_list,
        "initial": { "world_pos": initial_pos, "tail_world_pos": initial_tails },
        "samples": samples,
    });
    let text = serde_json::to_vec(&doc).map_err(|e| e.to_string())?;
    write_atomic(&a.out, &text)?;
    say!(
        "wrote {} ({} joints, {} frames, mode {mode_name})",
        a.out.display(),
        joints.len(),
        a.frames
    );
    Ok(())
}
