//! `tassel bench [FILE]`: ns per joint-step and µs per frame, for a synthetic character
//! (16 strands of 8 joints, 8 colliders) or the user's own file.

use crate::subject::Mode;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;
use tassel::crowd::{ChainCrowd, CrowdPose, Isa, SimdUse, VrmCrowd};
use tassel::dynamics::chain::ChainRig;
use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Transform};

/// Options of `tassel bench`.
#[derive(clap::Args)]
pub struct Args {
    /// Your own character (.glb, .gltf, .vrm): its VRM springs, and the chains, springs,
    /// cloths and ropes of --rig, on its rest pose carried along the bench's motion.
    /// Without it, the bench rig: 16 strands of 8 joints around 8 colliders.
    file: Option<PathBuf>,
    /// With FILE: a rig file (TOML); optional for a VRM.
    #[arg(long, requires = "file")]
    rig: Option<PathBuf>,
    /// Frames per measurement.
    #[arg(long, default_value_t = 2000)]
    frames: usize,
    /// Measurements (the median is reported).
    #[arg(long, default_value_t = 11)]
    runs: usize,
    /// Run the same joints and colliders as VRM spring bones in this mode instead of
    /// chains. With FILE: the mode of its solvers (default `fixed`).
    #[arg(long, value_enum)]
    vrm: Option<VrmBenchMode>,
    /// The bench rig's chains in `classic` mode (KawaiiPhysics 1.10's step each frame)
    /// instead of `fixed` (to set `fixed`'s cost beside it).
    #[arg(long, conflicts_with_all = ["vrm", "file", "cloth"])]
    classic: bool,
    /// The built-in character's skirt (one bone cloth, 4 leg capsules) instead.
    #[arg(long, conflicts_with_all = ["vrm", "file"])]
    cloth: bool,
    /// A crowd of this many characters, each on its own phase of the motion, advanced
    /// together every frame: chains and VRM springs (any mode) through the crowd path
    /// (`tassel::crowd`, lane groups of 16), the cloth one `CharacterSim` each.
    #[arg(long)]
    crowd: Option<usize>,
    /// Threads sharing the crowd.
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// With --crowd: character `i` runs the motion `i` times this many seconds ahead
    /// (its phase). The default spreads neighbours far apart on the motion's 2.1 s
    /// cycle; a small step makes the characters of each lane group move alike, which
    /// the crowd path runs faster (`ChainCrowd::swap` lets a game group its characters).
    #[arg(long, requires = "crowd", default_value_t = 0.37)]
    phase_step: f32,
    /// With --crowd: also time the single-character path (one `CharacterSim` per
    /// character, the same threads) in the same run and print the ratio.
    #[arg(long, requires = "crowd")]
    compare: bool,
    /// With --crowd: time the crowd as a game's frame leaves it: each character reads
    /// its own pose buffer, and 64 MiB are written before every frame (not timed), so
    /// the crowd's state and input come from memory rather than the caches (a game
    /// engine's frame touches far more than the crowd between two steps: the Bevy bench's
    /// crowd is about this slow). The crowd path only.
    #[arg(long, requires = "crowd")]
    cold: bool,
    /// With --crowd, VRM springs: the characters' animated poses stay as they are (only
    /// their transforms move, as in the Bevy bench without `--animated`), and the crowd is
    /// told so before every frame (`VrmCrowd::mark_pose_unchanged`, as the Bevy plugin
    /// marks the members no animation moved). The bench's poses never change; without
    /// this flag the crowd reads them all the same.
    #[arg(long, requires = "crowd")]
    still: bool,
    /// Which code runs the solvers that have a lane path (VRM springs, twin chains, the
    /// cloth's contact tests; with --crowd, the crowd): `scalar` is the readable
    /// reference (the same bits, slower; one character only), `portable` lanes without
    /// AVX, `avx2` lanes with AVX2 at most (how a CPU without AVX-512 runs `auto`),
    /// `auto` the widest the CPU has.
    #[arg(long, value_enum, default_value_t = SimdBench::Auto)]
    simd: SimdBench,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum SimdBench {
    Scalar,
    Portable,
    Avx2,
    Auto,
}

impl SimdBench {
    fn simd_use(self) -> SimdUse {
        match self {
            SimdBench::Scalar => SimdUse::Scalar,
            SimdBench::Portable => SimdUse::Portable,
            SimdBench::Avx2 => SimdUse::Avx2,
            SimdBench::Auto => SimdUse::Auto,
        }
    }

    /// What runs, for the report: "scalar reference" or "lanes (AVX-512)" and the like.
    fn describe(self) -> String {
        match self {
            SimdBench::Scalar => "scalar reference".into(),
            // A character's VRM springs take the scalar update where lanes would be slower.
            SimdBench::Auto => {
                format!(
                    "lanes ({}; one character's VRM springs where they pay)",
                    Isa::of(self.simd_use()).name()
                )
            }
            _ => format!("lanes ({})", Isa::of(self.simd_use()).name()),
        }
    }
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum VrmBenchMode {
    Spec,
    Fixed,
    ThreeVrm,
}

/// The user's file as a bench character, in the mode of `--vrm` (default fixed).
fn file_character(a: &Args, path: &PathBuf) -> Result<(CharacterSim, usize, String), String> {
    let subject = crate::subject::load(Some(path), false, a.rig.as_ref())?;
    let mode = match a.vrm.unwrap_or(VrmBenchMode::Fixed) {
        VrmBenchMode::Spec => Mode::Spec,
        VrmBenchMode::Fixed => Mode::Fixed,
        VrmBenchMode::ThreeVrm => Mode::ThreeVrm,
    };
    let (sim, mode) = subject.sim(Some(mode))?;
    let simulated = sim.simulated_joints().len();
    if simulated == 0 {
        return Err(format!("{}: nothing to simulate", subject.name));
    }
    let what = format!(
        "{} ({} nodes; {} VRM spring joints{}), {mode:?} mode, its rest pose on the bench motion, 60 Hz frames",
        subject.name,
        subject.skeleton.len(),
        sim.vrm().links.len(),
        if a.rig.is_some() { ", and its rig" } else { "" },
    );
    Ok((sim, simulated, what))
}

/// The bench rig's skeleton and chains, in `classic` mode with `--classic`.
fn bench_chains(
    a: &Args,
    chains: usize,
    joints: usize,
    colliders: usize,
) -> (tassel::Skeleton, RigSettings) {
    let (sk, mut rig) = builtin::bench_character(chains, joints, colliders);
    if a.classic {
        for c in &mut rig.chains {
            c.mode = tassel::dynamics::chain::TimeMode::Classic;
        }
    }
    (sk, rig)
}

/// One bench character: the simulation, how many joints it simulates, what it is.
fn character(a: &Args) -> Result<(CharacterSim, usize, String), String> {
    if let Some(path) = &a.file {
        return file_character(a, path);
    }
    let (chains, joints, colliders) = (16, 8, 8);
    let (sk, rig) = bench_chains(a, chains, joints, colliders);
    if a.cloth {
        let c = builtin::character();
        let rig = RigSettings {
            cloths: c.rig.cloths.clone(),
            colliders: c.rig.colliders.clone(),
            ..Default::default()
        };
        let sim = CharacterSim::new(c.skeleton, &rig).map_err(|e| e.to_string())?;
        let cloths = sim.cloths();
        let free = (0..cloths.point_count())
            .filter(|&p| !cloths.is_fixed(p))
            .count();
        return Ok((
            sim,
            free,
            "the built-in skirt (bone cloth, 4 leg capsules, 120 Hz steps), 60 Hz frames".into(),
        ));
    }
    match a.vrm {
        None => {
            let sim = CharacterSim::new(sk, &rig).map_err(|e| e.to_string())?;
            let simulated = sim.chains().point_count() - chains; // roots are not simulated
            Ok((
                sim,
                simulated,
                format!(
                    "{chains} chains x {joints} joints, {colliders} colliders, chains, {}",
                    if a.classic {
                        "classic mode, 60 Hz frames"
                    } else {
                        "fixed mode 60 Hz, one step per frame"
                    }
                ),
            ))
        }
        Some(m) => {
            let (_, bones) = builtin::bench_vrm(chains, joints, colliders);
            let options = vrm_options(m);
            let mode = options.mode;
            let sim = CharacterSim::with_vrm(sk, &RigSettings::default(), &bones, options)
                .map_err(|e| e.to_string())?;
            let simulated = sim.vrm().links.len();
            Ok((
                sim,
                simulated,
                format!("{chains} chains x {joints} joints, {colliders} colliders, VRM spring bones, {mode:?} mode, 60 Hz frames"),
            ))
        }
    }
}

/// The bench's VRM options in mode `m`.
fn vrm_options(m: VrmBenchMode) -> VrmOptions {
    VrmOptions {
        mode: match m {
            VrmBenchMode::Spec => VrmMode::Spec,
            VrmBenchMode::Fixed => VrmMode::Fixed,
            VrmBenchMode::ThreeVrm => VrmMode::ThreeVrm,
        },
        ..Default::default()
    }
}

/// One warm-up run of a quarter of `frames`, then `runs` runs of `frames`: the samples
/// `one_run(frames)` returns, sorted.
fn sorted_samples(
    runs: usize,
    frames: usize,
    mut one_run: impl FnMut(usize) -> Result<f64, String>,
) -> Result<Vec<f64>, String> {
    one_run(frames / 4 + 1)?; // warm up
    let mut samples = Vec::new();
    for _ in 0..runs.max(1) {
        samples.push(one_run(frames.max(1))?);
    }
    samples.sort_by(|x, y| x.total_cmp(y));
    Ok(samples)
}

/// The bench motion of a character with phase `phase` at frame `f`.
fn motion(f: usize, phase: f32) -> Transform {
    let t = f as f32 / 60.0 + phase;
    Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t))
}

pub fn run(a: Args) -> Result<(), String> {
    if let Some(n) = a.crowd {
        return crowd(&a, n);
    }
    let (mut sim, simulated, what) = character(&a)?;
    sim.set_simd(a.simd.simd_use());
    let rest = sim.skeleton().rest().to_vec();
    let dt = 1.0 / 60.0;
    let mut f = 0usize;
    let mut one_run = |frames: usize| -> Result<f64, String> {
        let start = Instant::now();
        for _ in 0..frames {
            f += 1;
            sim.frame(&rest, motion(f, 0.0), dt)
                .map_err(|e| e.to_string())?;
        }
        Ok(start.elapsed().as_nanos() as f64 / (frames * simulated) as f64)
    };
    let samples = sorted_samples(a.runs, a.frames, &mut one_run)?;
    let median = samples[samples.len() / 2];
    let code = a.simd.describe();
    say!("tassel bench: {what}, single thread, {code}");
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

/// `--crowd N --threads T`: N characters, each on its own phase, advanced frame by frame;
/// each thread takes a contiguous batch and all wait for each other at the end of every
/// frame (as a game's frame would). Prints the wall time per frame and per joint-step
/// (wall time / (N × joints × frames)), medians over the runs.
fn crowd(a: &Args, n: usize) -> Result<(), String> {
    if !(1..=1_000_000).contains(&n) {
        return Err(format!("--crowd {n} must be 1..=1000000"));
    }
    if !(1..=256).contains(&a.threads) {
        return Err(format!("--threads {} must be 1..=256", a.threads));
    }
    if !(a.phase_step.is_finite() && a.phase_step.abs() <= 1000.0) {
        return Err(format!(
            "--phase-step {} must be a number of seconds within ±1000",
            a.phase_step
        ));
    }
    let threads = a.threads.min(n);
    let frames = a.frames.max(1);
    if a.cold && a.compare {
        return Err("--cold times the crowd path only: leave out --compare".into());
    }
    // A file's character steps as a VRM crowd when its solvers are VRM springs alone,
    // else one `CharacterSim` each.
    let file_crowd = match &a.file {
        Some(_) => {
            let (sim, _, _) = character(a)?;
            let only_vrm = sim.simulated_joints().len() == sim.vrm().links.len();
            only_vrm.then(|| (sim.skeleton().clone(), sim.vrm().clone()))
        }
        None => None,
    };
    let crowd_path = !a.cloth && (a.file.is_none() || file_crowd.is_some());
    if a.cold && !crowd_path {
        return Err(
            "--cold times the crowd path only (VRM springs alone, or the bench chains)".into(),
        );
    }
    if a.still && !(crowd_path && (file_crowd.is_some() || a.vrm.is_some())) {
        return Err(
            "--still marks a VRM crowd's poses unchanged: it needs --vrm or a file with \
             VRM springs alone"
                .into(),
        );
    }
    if crowd_path && a.simd == SimdBench::Scalar {
        return Err(
            "--simd scalar: the crowd path has only lanes (its scalar reference is one \
             CharacterSim per character: --compare times it)"
                .into(),
        );
    }
    let reference = if !crowd_path || a.compare {
        Some(sims_crowd(a, n, threads, frames)?)
    } else {
        None
    };
    let (what, joints, per_frame, path) = if crowd_path {
        let (what, joints, t) = if let Some((sk, rig)) = file_crowd {
            let (_, joints, what) = character(a)?;
            crowd_of(a, n, threads, frames, what, joints, sk, rig)?
        } else if a.vrm.is_some() {
            vrm_crowd(a, n, threads, frames)?
        } else {
            chain_crowd(a, n, threads, frames)?
        };
        (
            what,
            joints,
            t,
            format!(
                "crowd path, {}{}{}",
                a.simd.describe(),
                if a.cold {
                    "; cold: a pose buffer per character, 64 MiB written before every frame (not timed)"
                } else {
                    ""
                },
                if a.still {
                    "; still: every pose marked unchanged"
                } else {
                    ""
                }
            ),
        )
    } else {
        let (what, joints, t) = reference.clone().expect("timed above");
        (
            what,
            joints,
            t,
            "one CharacterSim per character".to_string(),
        )
    };
    say!(
        "tassel bench --crowd: {what}; {path}; character i at i x {} s on the motion; median of {} runs x {frames} frames",
        a.phase_step,
        a.runs.max(1)
    );
    if let (true, Some((_, _, r))) = (crowd_path, &reference) {
        say!(
            "  single-character path, same run: {:.3} ms per frame, {:.1} ns per joint-step: the crowd path is {:.1}x faster",
            r * 1e3,
            r * 1e9 / (n * joints) as f64,
            r / per_frame
        );
    }
    say!(
        "crowd: {n} characters x {joints} joints, {threads} threads: {:.3} ms per frame, {:.1} ns per joint-step",
        per_frame * 1e3,
        per_frame * 1e9 / (n * joints) as f64
    );
    Ok(())
}

/// The chain crowd path: seconds per frame (median), with what was run.
fn chain_crowd(
    a: &Args,
    n: usize,
    threads: usize,
    frames: usize,
) -> Result<(String, usize, f64), String> {
    let (_, joints, what) = character(a)?;
    let (sk, settings) = bench_chains(a, 16, 8, 8);
    let rig = ChainRig::new(&sk, &settings).map_err(|e| e.to_string())?;
    let mut poses = Poses::new(a, n, sk.rest())?;
    let mut crowd = ChainCrowd::new(Arc::new(sk), Arc::new(rig)).map_err(|e| e.to_string())?;
    crowd.set_simd(a.simd.simd_use());
    for _ in 0..n {
        crowd.add();
    }
    time_crowd(a, threads, frames, what, joints, |f| {
        poses.sweep();
        let start = Instant::now();
        crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: motion(f, i as f32 * a.phase_step),
                locals: poses.of(i),
            })
            .map_err(|e| e.to_string())?;
        Ok(start.elapsed().as_secs_f64())
    })
}

/// The crowd's animated poses: the rest pose shared by every character, or with
/// `--cold` a copy per character and a buffer to sweep the caches with.
struct Poses {
    rest: Vec<Transform>,
    own: Vec<Transform>,
    sweep: Vec<u64>,
}

impl Poses {
    /// Bytes `--cold` writes before every frame: twice this machine's last-level cache
    /// (32 MiB; a processor with a larger one keeps part of the crowd in it).
    const SWEEP_BYTES: usize = 64 << 20;
    /// The most the per-character poses of `--cold` may take.
    const MAX_OWN_BYTES: usize = 2 << 30;

    fn new(a: &Args, n: usize, rest: &[Transform]) -> Result<Poses, String> {
        let mut p = Poses {
            rest: rest.to_vec(),
            own: Vec::new(),
            sweep: Vec::new(),
        };
        if a.cold {
            let bytes = n
                .saturating_mul(rest.len())
                .saturating_mul(std::mem::size_of::<Transform>());
            if bytes > Self::MAX_OWN_BYTES {
                return Err(format!(
                    "--cold: {n} characters' own poses would take {} MiB (at most {} MiB)",
                    bytes >> 20,
                    Self::MAX_OWN_BYTES >> 20
                ));
            }
            p.own = (0..n).flat_map(|_| rest.iter().copied()).collect();
            p.sweep = vec![0; Self::SWEEP_BYTES / 8];
        }
        Ok(p)
    }

    /// Character `i`'s pose.
    fn of(&self, i: usize) -> &[Transform] {
        let n = self.rest.len();
        self.own.get(i * n..(i + 1) * n).unwrap_or(&self.rest)
    }

    /// With `--cold`: writes the sweep buffer (pushing the crowd out of the caches).
    fn sweep(&mut self) {
        for (k, x) in self.sweep.iter_mut().enumerate() {
            *x = x.wrapping_add(k as u64);
        }
        std::hint::black_box(&mut self.sweep);
    }
}

/// Times frames `f` = 0, 1, ... on a pool of `threads` (`frame(f)` runs a frame and
/// returns the seconds it took, leaving out any preparation): seconds per frame (median
/// over the runs), with what was run.
fn time_crowd(
    a: &Args,
    threads: usize,
    frames: usize,
    what: String,
    joints: usize,
    mut frame: impl FnMut(usize) -> Result<f64, String> + Send,
) -> Result<(String, usize, f64), String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let mut first_frame = 0usize;
    let one_run = |frames: usize| -> Result<f64, String> {
        let seconds = pool.install(|| -> Result<f64, String> {
            let mut seconds = 0.0;
            for f in first_frame..first_frame + frames {
                seconds += frame(f)?;
            }
            Ok(seconds)
        })?;
        first_frame += frames;
        Ok(seconds / frames as f64)
    };
    let samples = sorted_samples(a.runs, frames, one_run)?;
    Ok((what, joints, samples[samples.len() / 2]))
}

/// The VRM crowd path: seconds per frame (median), with what was run.
fn vrm_crowd(
    a: &Args,
    n: usize,
    threads: usize,
    frames: usize,
) -> Result<(String, usize, f64), String> {
    let (_, joints, what) = character(a)?;
    let (sk, bones) = builtin::bench_vrm(16, 8, 8);
    let options = vrm_options(a.vrm.unwrap_or(VrmBenchMode::Spec));
    let rig = VrmRig::new(&sk, &bones, options).map_err(|e| e.to_string())?;
    crowd_of(a, n, threads, frames, what, joints, sk, rig)
}

/// A VRM crowd of `n` characters of one kind (`sk`, `rig`) on the bench motion: seconds
/// per frame (median).
#[allow(clippy::too_many_arguments)]
fn crowd_of(
    a: &Args,
    n: usize,
    threads: usize,
    frames: usize,
    what: String,
    joints: usize,
    sk: tassel::Skeleton,
    rig: VrmRig,
) -> Result<(String, usize, f64), String> {
    let mut poses = Poses::new(a, n, sk.rest())?;
    let mut crowd = VrmCrowd::new(Arc::new(sk), Arc::new(rig)).map_err(|e| e.to_string())?;
    crowd.set_simd(a.simd.simd_use());
    for _ in 0..n {
        crowd.add();
    }
    time_crowd(a, threads, frames, what, joints, |f| {
        poses.sweep();
        let start = Instant::now();
        if a.still && f > 0 {
            for i in 0..n {
                crowd.mark_pose_unchanged(i).map_err(|e| e.to_string())?;
            }
        }
        crowd
            .frame(1.0 / 60.0, |i| CrowdPose {
                transform: motion(f, i as f32 * a.phase_step),
                locals: poses.of(i),
            })
            .map_err(|e| e.to_string())?;
        Ok(start.elapsed().as_secs_f64())
    })
}

/// The single-character path for a crowd: one `CharacterSim` per character, threads
/// taking contiguous batches and meeting at the end of every frame. Seconds per frame
/// (median), with what was run.
fn sims_crowd(
    a: &Args,
    n: usize,
    threads: usize,
    frames: usize,
) -> Result<(String, usize, f64), String> {
    let mut sims = Vec::with_capacity(n);
    let mut joints = 0;
    let mut what = String::new();
    for _ in 0..n {
        let (mut sim, j, w) = character(a)?;
        sim.set_simd(a.simd.simd_use());
        sims.push(sim);
        (joints, what) = (j, w);
    }
    let rest = sims[0].skeleton().rest().to_vec();
    let batch = n.div_ceil(threads);
    let (dt, phase_step) = (1.0 / 60.0, a.phase_step);
    let mut first_frame = 0usize;
    let mut one_run = |sims: &mut [CharacterSim], frames: usize| -> Result<f64, String> {
        let barrier = std::sync::Barrier::new(threads);
        let start = Instant::now();
        let results: Vec<Result<(), String>> = std::thread::scope(|scope| {
            let handles: Vec<_> = sims
                .chunks_mut(batch)
                .enumerate()
                .map(|(b, chunk)| {
                    let (barrier, rest) = (&barrier, &rest);
                    scope.spawn(move || -> Result<(), String> {
                        for f in first_frame..first_frame + frames {
                            for (k, sim) in chunk.iter_mut().enumerate() {
                                let phase = (b * batch + k) as f32 * phase_step;
                                sim.frame(rest, motion(f, phase), dt)
                                    .map_err(|e| e.to_string())?;
                            }
                            barrier.wait();
                        }
                        Ok(())
                    })
                })
                .collect();
            handles.into_iter().map(|h| h.join().unwrap()).collect()
        });
        results.into_iter().collect::<Result<(), String>>()?;
        first_frame += frames;
        Ok(start.elapsed().as_secs_f64() / frames as f64)
    };
    let samples = sorted_samples(a.runs, frames, |frames| one_run(&mut sims, frames))?;
    Ok((what, joints, samples[samples.len() / 2]))
}
