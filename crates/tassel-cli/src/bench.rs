//! `tassel bench`: ns per joint-step for a synthetic character, single thread.

use std::time::Instant;
use tassel::{builtin, CharacterSim, Transform};

/// Options of `tassel bench`.
#[derive(clap::Args)]
pub struct Args {
    /// Frames per measurement.
    #[arg(long, default_value_t = 2000)]
    frames: usize,
    /// Measurements (the median is reported).
    #[arg(long, default_value_t = 11)]
    runs: usize,
}

pub fn run(a: Args) -> Result<(), String> {
    let (chains, joints, colliders) = (16, 8, 8);
    let (sk, rig) = builtin::bench_character(chains, joints, colliders);
    let mut sim = CharacterSim::new(sk.clone(), &rig).map_err(|e| e.to_string())?;
    let rest = sk.rest().to_vec();
    let simulated = sim.chains().point_count() - chains; // roots are not simulated
    let dt = 1.0 / 60.0;
    let mut f = 0usize;
    let mut one_run = |frames: usize| -> Result<f64, String> {
        let start = Instant::now();
        for _ in 0..frames {
            f += 1;
            let t = f as f32 * dt;
            let comp = Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t));
            sim.frame(&rest, comp, dt).map_err(|e| e.to_string())?;
        }
        Ok(start.elapsed().as_nanos() as f64 / (frames * simulated) as f64)
    };
    one_run(a.frames / 4 + 1)?; // warm up
    let mut samples = Vec::new();
    for _ in 0..a.runs.max(1) {
        samples.push(one_run(a.frames.max(1))?);
    }
    samples.sort_by(|x, y| x.total_cmp(y));
    let median = samples[samples.len() / 2];
    say!("tassel bench: {chains} chains x {joints} joints, {colliders} colliders, fixed mode 60 Hz, one step per frame, single thread");
    say!(
        "  {simulated} simulated joints; median of {} runs x {} frames",
        samples.len(),
        a.frames
    );
    say!(
        "  {median:.1} ns per joint-step (frame incl. pose jobs and write-back: {:.2} us)",
        median * simulated as f64 / 1000.0
    );
    say!(
        "  min {:.1}  max {:.1} ns per joint-step",
        samples[0],
        samples[samples.len() - 1]
    );
    Ok(())
}
