//! `tassel plot`: how far a tip strays from its animated position over time, one line per
//! mode and frame rate, for the same motion; or, with `--wind NAME`, a procedural wind's
//! parts over time (KawaiiPhysics' Wind Scope).

use crate::output::{check_output_dir, write_atomic};
use crate::subject::Mode;
use crate::subject::{SubjectArgs, SwayArgs};
use std::path::PathBuf;
use tassel_gltf::{key_times, play, BakeOptions};
use tassel_render::{Chart, ChartSeries, PALETTE};

/// Options of `tassel plot`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    subject: SubjectArgs,
    /// The joint whose displacement is plotted. Default: the deepest joint of a chain or
    /// VRM spring (else of any solver).
    #[arg(long)]
    joint: Option<String>,
    /// Modes to compare, comma-separated. Default: fixed,classic (spec,fixed for a model
    /// whose only springs are VRM springs).
    #[arg(long, value_delimiter = ',', value_enum)]
    modes: Vec<Mode>,
    /// Frame rates to compare, comma-separated, Hz.
    #[arg(long, value_delimiter = ',', default_value = "60")]
    rates: Vec<f32>,
    /// Seconds the clip plays, looped, before the plot starts (the same for every line).
    #[arg(long, default_value_t = 0.0)]
    warmup: f32,
    #[command(flatten)]
    sway: SwayArgs,
    /// Seconds plotted (default: the clip's length, or 3 s for the rest pose; 10 s of a
    /// wind).
    #[arg(long)]
    duration: Option<f32>,
    /// Plot the parts of the rig's procedural wind named NAME over time instead (an
    /// `[[external_force]]` with `kind = "procedural_wind"`): constant, sway, the ripple at
    /// the root and at the tip, the strength cycle, the noise, the total at the root and
    /// at the tip, sampled on the wind's own clock (its `time_scale` applied) at the first
    /// of --rates.
    #[arg(long, value_name = "NAME")]
    wind: Option<String>,
    /// Output PNG.
    #[arg(short, long)]
    out: PathBuf,
}

pub fn run(a: Args) -> Result<(), String> {
    if a.out.extension().map(|e| e.to_ascii_lowercase()) != Some("png".into()) {
        return Err(format!("{}: the chart is written as .png", a.out.display()));
    }
    check_output_dir(&a.out)?;
    for &r in &a.rates {
        if !(r.is_finite() && (1.0..=1000.0).contains(&r)) {
            return Err(format!("--rates: {r} must be a frame rate in 1..=1000 Hz"));
        }
    }
    let (subject, clip) = a.subject.load()?;
    if let Some(name) = &a.wind {
        return plot_wind(&a, &subject, name);
    }
    let clip = clip.map(|i| &subject.clips[i]);
    let modes = if !a.modes.is_empty() {
        a.modes.clone()
    } else if !subject.vrm.is_empty() && subject.rig.chains.is_empty() {
        vec![Mode::Spec, Mode::Fixed]
    } else {
        vec![Mode::Fixed, Mode::Classic]
    };
    let duration = match a.duration {
        Some(d) if d.is_finite() && d > 0.0 && d <= 600.0 => d,
        Some(d) => return Err(format!("--duration {d} must be in (0, 600] seconds")),
        None => clip.map(|c| c.duration).filter(|d| *d > 0.0).unwrap_or(3.0),
    };
    // The joint: named, or the deepest chain or VRM spring joint.
    let (probe, _) = subject.sim(Some(modes[0]))?;
    let simulated = probe.simulated_joints();
    let sk = &subject.skeleton;
    let joint = match &a.joint {
        Some(name) => sk
            .find(name)
            .ok_or_else(|| format!("--joint: the skeleton has no joint named '{name}'"))?,
        None => {
            // Prefer the tips of chains and VRM springs (what the modes change), then any
            // simulated joint.
            let chains = probe.chains();
            let mut tips: Vec<usize> = (0..chains.point_count())
                .filter_map(|p| {
                    let info = chains.point(p);
                    info.parent.and(info.joint)
                })
                .chain(probe.vrm().simulated_joints())
                .collect();
            if tips.is_empty() {
                tips = simulated.to_vec();
            }
            *tips
                .iter()
                .max_by_key(|&&j| (depth(sk, j), std::cmp::Reverse(j)))
                .ok_or("nothing to plot: the rig and the file's VRM springs simulate no bone")?
        }
    };
    let mut series = Vec::new();
    for (mi, &mode) in modes.iter().enumerate() {
        for (ri, &rate) in a.rates.iter().enumerate() {
            let (mut sim, m) = subject.sim(Some(mode))?;
            let options = BakeOptions {
                fps: rate,
                warmup: a.warmup,
                rest_duration: duration,
                sway: a.sway.sway(),
            };
            let times = key_times(duration, rate);
            let mut points = Vec::with_capacity(times.len());
            play(&mut sim, clip, &times, &options, &mut |f| {
                let c = &f.component;
                let out = c.transform_point(f.sim.pose().models[joint].translation);
                let anim = c.transform_point(f.sim.animated_models()[joint].translation);
                points.push((f.time, (out - anim).length()));
                Ok::<(), String>(())
            })
            .map_err(|e| e.to_string())?;
            series.push(ChartSeries {
                name: format!("{} {} HZ", m.name(), rate),
                color: PALETTE[(mi * a.rates.len() + ri) % PALETTE.len()],
                points,
            });
        }
    }
    let units = if a.subject.builtin { "M" } else { "FILE UNITS" };
    let chart = Chart {
        title: format!(
            "{} - {} - {}",
            subject.name,
            clip.map(|c| c.name.as_str()).unwrap_or("REST"),
            sk.name(joint)
        ),
        x_label: "TIME (S)".into(),
        y_label: format!("TIP DISPLACEMENT FROM THE ANIMATION ({units})"),
        series,
        bands: vec![],
    };
    let png = chart.draw(900, 480).png().map_err(|e| e.to_string())?;
    write_atomic(&a.out, &png)?;
    let largest: Vec<String> = chart
        .series
        .iter()
        .map(|s| {
            let m = s.points.iter().map(|p| p.1).fold(0.0f32, f32::max);
            format!("{} max {m:.4}", s.name.to_lowercase())
        })
        .collect();
    say!(
        "wrote {} (joint '{}': {})",
        a.out.display(),
        sk.name(joint),
        largest.join(", ")
    );
    Ok(())
}

fn depth(sk: &tassel::Skeleton, mut j: usize) -> usize {
    let mut d = 0;
    while let Some(p) = sk.parent(j) {
        d += 1;
        j = p;
    }
    d
}

/// `--wind NAME`: the procedural wind's parts over `--duration` seconds (default 10).
fn plot_wind(a: &Args, subject: &crate::subject::Subject, name: &str) -> Result<(), String> {
    use tassel::dynamics::chain::ForceKind;
    let force = subject
        .rig
        .external_forces
        .iter()
        .find(|f| f.name == name)
        .ok_or_else(|| format!("--wind: the rig has no external force named '{name}'"))?;
    if force.kind != ForceKind::ProceduralWind {
        return Err(format!(
            "--wind: external force '{name}' is not a procedural wind (kind = \"procedural_wind\")"
        ));
    }
    force.validate().map_err(|e| e.to_string())?;
    let duration = match a.duration {
        Some(d) if d.is_finite() && d > 0.0 && d <= 600.0 => d,
        Some(d) => return Err(format!("--duration {d} must be in (0, 600] seconds")),
        None => 10.0,
    };
    let rate = a.rates.first().copied().unwrap_or(60.0);
    let w = &force.procedural_wind;
    let steps = (duration * rate).round() as usize;
    let names = [
        "CONSTANT",
        "SWAY",
        "RIPPLE ROOT",
        "RIPPLE TIP",
        "STRENGTH CYCLE",
        "RANDOM",
        "TOTAL ROOT",
        "TOTAL TIP",
    ];
    let mut lines: Vec<Vec<(f32, f32)>> = vec![Vec::with_capacity(steps + 1); names.len()];
    for k in 0..=steps {
        let t = k as f32 / rate;
        // The wind's own clock runs at `time_scale`.
        let clock = t * w.time_scale;
        let root = w.sample(clock, 0.0, 0.0, force.seed);
        let tip = w.sample(clock, 1.0, 0.0, force.seed);
        let values = [
            root.constant,
            root.sway,
            root.ripple,
            tip.ripple,
            root.strength_cycle,
            root.random,
            root.total,
            tip.total,
        ];
        for (line, v) in lines.iter_mut().zip(values) {
            line.push((t, v));
        }
    }
    let series: Vec<ChartSeries> = names
        .iter()
        .zip(lines)
        .enumerate()
        .map(|(i, (n, points))| ChartSeries {
            name: n.to_string(),
            color: PALETTE[i % PALETTE.len()],
            points,
        })
        .collect();
    let chart = Chart {
        title: format!("{} - PROCEDURAL WIND {}", subject.name, name.to_uppercase()),
        x_label: "TIME (S)".into(),
        y_label: "WIND PARTS (PUSH UNITS) - STRENGTH CYCLE IS A MULTIPLIER".into(),
        series,
        bands: vec![],
    };
    let png = chart.draw(900, 480).png().map_err(|e| e.to_string())?;
    write_atomic(&a.out, &png)?;
    let range: Vec<String> = chart
        .series
        .iter()
        .map(|s| {
            let lo = s.points.iter().map(|p| p.1).fold(f32::INFINITY, f32::min);
            let hi = s
                .points
                .iter()
                .map(|p| p.1)
                .fold(f32::NEG_INFINITY, f32::max);
            format!("{} {lo:.3}..{hi:.3}", s.name.to_lowercase())
        })
        .collect();
    say!(
        "wrote {} (wind '{name}' over {duration} s: {})",
        a.out.display(),
        range.join(", ")
    );
    Ok(())
}
