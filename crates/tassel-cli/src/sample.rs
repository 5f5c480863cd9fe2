//! `tassel sample`: sampled (and blended) local and world transforms of every node.

use crate::output::{write_atomic_with, JsonStream};
use serde_json::json;
use std::path::PathBuf;
use tassel::anim::{BlendJob, BlendLayer, Playback, SamplingCursor, SamplingJob};
use tassel::{LocalToModelJob, Transform};

/// Options of `tassel sample`.
#[derive(clap::Args)]
pub struct Args {
    /// The model (.glb, .gltf).
    model: PathBuf,
    /// The clip: a name or an index.
    #[arg(long)]
    clip: String,
    /// More clips to blend in, as NAME:WEIGHT (or INDEX:WEIGHT); repeatable.
    #[arg(long)]
    blend: Vec<String>,
    /// Weight of --clip.
    #[arg(long, default_value_t = 1.0)]
    weight: f32,
    /// Comma-separated times in seconds.
    #[arg(long, value_delimiter = ',', conflicts_with_all = ["fps", "duration"])]
    times: Vec<f32>,
    /// Sample rate (with --duration).
    #[arg(long, requires = "duration")]
    fps: Option<f32>,
    /// Length to sample, seconds (with --fps).
    #[arg(long, requires = "fps")]
    duration: Option<f32>,
    /// Output JSON file.
    #[arg(long)]
    out: PathBuf,
}

fn find_clip(names: &[&str], key: &str) -> Result<usize, String> {
    if let Some(i) = names.iter().position(|n| *n == key) {
        return Ok(i);
    }
    match key.parse::<usize>() {
        Ok(i) if i < names.len() => Ok(i),
        _ => Err(format!(
            "no clip '{key}'; the file has: {}",
            names.join(", ")
        )),
    }
}

pub fn run(a: Args) -> Result<(), String> {
    let model = tassel_gltf::load(&a.model).map_err(|e| e.to_string())?;
    let names: Vec<&str> = model.clips.iter().map(|c| c.name.as_str()).collect();
    let mut picks = vec![(find_clip(&names, &a.clip)?, a.weight)];
    for b in &a.blend {
        let (key, w) = b
            .rsplit_once(':')
            .ok_or_else(|| format!("--blend '{b}': expected NAME:WEIGHT"))?;
        let w: f32 = w
            .parse()
            .map_err(|_| format!("--blend '{b}': '{w}' is not a number"))?;
        picks.push((find_clip(&names, key)?, w));
    }
    if let Some(&(_, w)) = picks.iter().find(|p| !(p.1.is_finite() && p.1 >= 0.0)) {
        return Err(format!("weight {w} must be finite and ≥ 0"));
    }
    let times: Vec<f32> = match (a.fps, a.duration) {
        (Some(fps), Some(d)) => {
            if !(fps.is_finite()
                && fps > 0.0
                && fps <= 10_000.0
                && d.is_finite()
                && d >= 0.0
                && d * fps <= 1e6)
            {
                return Err(format!("--fps {fps} --duration {d}: need 0 < fps ≤ 10000, duration ≥ 0, at most 1e6 samples"));
            }
            let n = (d * fps).floor() as usize;
            (0..=n).map(|k| k as f32 / fps).collect()
        }
        _ => a.times.clone(),
    };
    if times.is_empty() || times.iter().any(|t| !t.is_finite()) {
        return Err("give --times (finite, comma-separated) or --fps with --duration".into());
    }
    let sk = &model.skeleton;
    let n = sk.len();
    let rest = sk.rest().to_vec();
    let mut cursors: Vec<SamplingCursor> = picks
        .iter()
        .map(|p| SamplingCursor::new(&model.clips[p.0]))
        .collect();
    let mut sampled: Vec<Vec<Transform>> = vec![rest.clone(); picks.len()];
    let mut locals = rest.clone();
    let mut models = rest.clone();
    // Output in glTF node order.
    let order: Vec<usize> = (0..n).map(|node| model.node_to_joint[node]).collect();
    let head = json!({
        "clips": picks.iter().map(|p| json!({ "name": names[p.0], "index": p.0, "weight": p.1 })).collect::<Vec<_>>(),
        "times": times,
        "nodes": (0..n).map(|node| json!({ "node": node, "name": sk.name(model.node_to_joint[node]) })).collect::<Vec<_>>(),
    });
    // Streamed time by time: a long, dense sampling never sits in memory.
    write_atomic_with(&a.out, |out| {
        let mut doc = JsonStream::begin(out, &head, "samples")?;
        for &t in &times {
            for (k, &(c, _)) in picks.iter().enumerate() {
                sampled[k].copy_from_slice(&rest);
                SamplingJob {
                    clip: &model.clips[c],
                    cursor: &mut cursors[k],
                    time: t,
                    playback: Playback::Clamp,
                    locals: &mut sampled[k],
                }
                .run()
                .map_err(|e| e.to_string())?;
            }
            let layers: Vec<BlendLayer> = picks
                .iter()
                .zip(&sampled)
                .map(|(p, l)| BlendLayer {
                    locals: l,
                    weight: p.1,
                    mask: None,
                })
                .collect();
            BlendJob {
                rest: &rest,
                layers: &layers,
                additive: &[],
                out: &mut locals,
            }
            .run()
            .map_err(|e| e.to_string())?;
            LocalToModelJob {
                skeleton: sk,
                root: Transform::IDENTITY,
                locals: &locals,
                models: &mut models,
            }
            .run()
            .map_err(|e| e.to_string())?;
            let sample = json!({
                "t": t,
                "local_t": order.iter().map(|&j| locals[j].translation.to_array()).collect::<Vec<_>>(),
                "local_r": order.iter().map(|&j| locals[j].rotation.to_array()).collect::<Vec<_>>(),
                "local_s": order.iter().map(|&j| locals[j].scale.to_array()).collect::<Vec<_>>(),
                "world_pos": order.iter().map(|&j| models[j].translation.to_array()).collect::<Vec<_>>(),
            });
            doc.push(&sample, &format!("time {t}"))?;
        }
        doc.end()
    })?;
    say!(
        "wrote {} ({} nodes, {} times)",
        a.out.display(),
        n,
        times.len()
    );
    Ok(())
}
