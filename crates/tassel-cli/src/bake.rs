//! `tassel bake`: a model's clips with their secondary motion keyed in, written as GLB.

use crate::output::{check_output_dir, write_atomic};
use crate::progress::Progress;
use crate::subject::Mode;
use crate::subject::{make_sim, rig_or_vrm, SwayArgs};
use std::path::PathBuf;
use tassel::CharacterSim;
use tassel_gltf::{bake_clip, export_glb, BakeOptions, BakeSource, Model};

/// Options of `tassel bake`.
#[derive(clap::Args)]
pub struct Args {
    /// The model (.glb, .gltf, .vrm).
    input: PathBuf,
    /// Rig file (TOML) with chains, springs, cloths, ropes and colliders; optional for a
    /// VRM (its spring bones run in any case).
    #[arg(long)]
    rig: Option<PathBuf>,
    /// A clip to bake, by name (repeatable). Default: every clip.
    #[arg(long, conflicts_with = "all_clips")]
    clip: Vec<String>,
    /// Bake every clip (the default).
    #[arg(long)]
    all_clips: bool,
    /// Keys per second of the baked bones.
    #[arg(long, default_value_t = 60.0)]
    fps: f32,
    /// fixed (default for VRM): VRM springs and chains at a fixed rate, the same look at
    /// every frame rate; spec: VRM springs by the specification; classic: chains frame by
    /// frame. Default for a rig: what the rig says.
    #[arg(long, value_enum)]
    mode: Option<Mode>,
    /// Seconds each clip plays, looped, before its first key, so that the motion starts
    /// settled.
    #[arg(long, default_value_t = 1.0)]
    warmup: f32,
    /// For a file without clips: length of the `rest` clip baked instead (the rest pose
    /// held while the secondary motion settles), seconds.
    #[arg(long, default_value_t = 2.0)]
    rest_duration: f32,
    #[command(flatten)]
    sway: SwayArgs,
    /// Output file (GLB, also for a .vrm input).
    #[arg(short, long)]
    out: PathBuf,
}

pub fn run(a: Args) -> Result<(), String> {
    check_output_dir(&a.out)?;
    let options = BakeOptions {
        fps: a.fps,
        warmup: a.warmup,
        rest_duration: a.rest_duration,
        sway: a.sway.sway(),
    };
    options.validate().map_err(|e| e.to_string())?;
    let model = tassel_gltf::load(&a.input).map_err(|e| e.to_string())?;
    let sources = choose_clips(&model, &a)?;
    let mut sim = build_sim(&model, a.rig.as_ref(), a.mode, &a.input)?;
    let joints = sim.simulated_joints().to_vec();
    if joints.is_empty() {
        return Err(format!(
            "{}: nothing to bake: the rig and the file's VRM springs simulate no bone",
            a.input.display()
        ));
    }
    let mut baked = Vec::new();
    let mut summary = Vec::new();
    for source in sources {
        let name = source.name(&model, &options);
        let mut bar = Progress::new(&format!("baking '{name}'"));
        let clip = bake_clip(&model, &mut sim, source, &options, &mut |d, t| {
            bar.update(d, t)
        })
        .map_err(|e| e.to_string())?;
        bar.finish();
        summary.push(format!("'{}' {} keys", clip.name, clip.times.len()));
        baked.push(clip);
    }
    let glb = export_glb(&model.source, &baked).map_err(|e| e.to_string())?;
    write_atomic(&a.out, &glb)?;
    say!(
        "wrote {} ({} bytes): {} with {} simulated bone(s) ({})",
        a.out.display(),
        glb.len(),
        summary.join(", "),
        joints.len(),
        joints
            .iter()
            .map(|&j| model.skeleton.name(j))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// The clips named on the command line, or all; a file without clips gets the rest clip.
fn choose_clips(model: &Model, a: &Args) -> Result<Vec<BakeSource>, String> {
    if a.clip.is_empty() {
        if model.clips.is_empty() {
            return Ok(vec![BakeSource::Rest]);
        }
        return Ok((0..model.clips.len()).map(BakeSource::Clip).collect());
    }
    let mut out = Vec::new();
    for name in &a.clip {
        let i = model
            .clips
            .iter()
            .position(|c| &c.name == name)
            .ok_or_else(|| {
                let names: Vec<String> = model
                    .clips
                    .iter()
                    .map(|c| format!("'{}'", c.name))
                    .collect();
                format!(
                    "{}: no clip named '{name}'; the file has {}",
                    a.input.display(),
                    if names.is_empty() {
                        "no clips".to_string()
                    } else {
                        names.join(", ")
                    }
                )
            })?;
        if !out.contains(&BakeSource::Clip(i)) {
            out.push(BakeSource::Clip(i));
        }
    }
    Ok(out)
}

/// The character's solvers: the file's VRM springs and the rig's chains, springs, cloths
/// and ropes, stepped in `mode`.
fn build_sim(
    model: &Model,
    rig_path: Option<&PathBuf>,
    mode: Option<Mode>,
    input: &std::path::Path,
) -> Result<CharacterSim, String> {
    let vrm = model
        .vrm
        .as_ref()
        .map(|v| v.springs.clone())
        .unwrap_or_default();
    let rig = rig_or_vrm(rig_path, !vrm.is_empty(), input)?;
    let (sim, _) = make_sim(&model.skeleton, &vrm, &rig, mode).map_err(|e| match rig_path {
        Some(p) if e.starts_with("rig: ") => format!("{}: {}", p.display(), &e[5..]),
        _ => e,
    })?;
    Ok(sim)
}
