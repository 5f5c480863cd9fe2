//! A crowd of swaying avatars in a headless Bevy app: what the plugin costs per frame.
//!
//! ```text
//! cargo run --release -p tassel-bevy --example crowd -- [N] [--mode fixed|spec] [--frames F] [--own] [--threads T]
//! cargo run --release -p tassel-bevy --features gltf --example crowd -- N path/to/avatar.vrm
//! ```
//! N characters (default 1 000) of one kind, each on its own phase of a sway, 60 frames a
//! second of game time. Without a file each is the built-in bench avatar: two strands of
//! eight VRM spring joints and four sphere colliders (16 joints). `--own` keeps every
//! character on its own `CharacterSim` (the plugin's path for kinds a crowd cannot take)
//! instead of its kind's crowd. `--threads T` gives Bevy's compute task pool T threads
//! (Bevy's default on two cores is one: its I/O and async pools take a thread each).
//! Prints the plugin's step (`tassel_bevy::STEP_TIME`: read,
//! step and write-back of every character) in ms per frame and ns per joint-step, and the
//! whole frame (`App::update`) against the same app whose characters have no
//! `SecondaryMotion`; medians.

use bevy::asset::AssetPlugin;
use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use std::time::{Duration, Instant};
use tassel::dynamics::SimMode;
use tassel_bevy::prelude::*;
use tassel_bevy::{READ_TIME, SOLVE_TIME, STEP_TIME, WRITE_TIME};

struct Options {
    n: usize,
    file: Option<std::path::PathBuf>,
    mode: SimMode,
    frames: usize,
    own: bool,
    threads: Option<usize>,
}

fn options() -> Result<Options, String> {
    let mut o = Options {
        n: 1000,
        file: None,
        mode: SimMode::Fixed,
        frames: 200,
        own: false,
        threads: None,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = |name: &str| args.next().ok_or(format!("{name} needs a value"));
        match a.as_str() {
            "--mode" => {
                o.mode = match value("--mode")?.as_str() {
                    "fixed" => SimMode::Fixed,
                    "spec" => SimMode::Spec,
                    m => return Err(format!("--mode {m}: fixed or spec")),
                }
            }
            "--frames" => {
                o.frames = value("--frames")?
                    .parse()
                    .map_err(|e| format!("--frames: {e}"))?
            }
            "--own" => o.own = true,
            "--threads" => {
                o.threads = Some(
                    value("--threads")?
                        .parse()
                        .map_err(|e| format!("--threads: {e}"))?,
                )
            }
            _ if a.parse::<usize>().is_ok() => o.n = a.parse().unwrap(),
            _ if !a.starts_with('-') => o.file = Some(a.into()),
            _ => return Err(format!("unknown option {a}")),
        }
    }
    if o.n == 0 || o.n > 100_000 || o.frames == 0 || o.frames > 100_000 {
        return Err("N and --frames: 1 to 100 000".into());
    }
    Ok(o)
}

/// Sways its entity, `.0` seconds ahead on the motion.
#[derive(Component)]
struct Sway(f32);

fn sway(time: Res<Time>, mut q: Query<(&mut Transform, &Sway)>) {
    for (mut t, s) in &mut q {
        let x = time.elapsed_secs() + s.0;
        t.translation.x = 0.3 * (2.0 * x).sin();
        t.rotation = Quat::from_rotation_y(0.5 * (1.3 * x).sin());
    }
}

/// A headless app: time advances 1/60 s per update; `threads` for the compute pool.
fn app(folder: &str, threads: Option<usize>) -> App {
    let mut tasks = TaskPoolPlugin::default();
    if let Some(n) = threads {
        tasks.task_pool_options.compute = bevy::app::TaskPoolThreadAssignmentPolicy {
            min_threads: n,
            max_threads: n,
            percent: 1.0,
            on_thread_spawn: None,
            on_thread_destroy: None,
        };
    }
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins.set(tasks),
        AssetPlugin {
            file_path: folder.to_string(),
            ..default()
        },
        TransformPlugin,
    ))
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )))
    .add_plugins(TasselPlugin)
    .add_systems(Update, sway);
    app
}

/// The character's `SecondaryMotion`, when the run has secondary motion.
fn motion(model: &Handle<TasselModel>, o: &Options, with_motion: bool) -> Option<SecondaryMotion> {
    let m = SecondaryMotion::new(model.clone()).with_mode(o.mode);
    with_motion.then(|| if o.own { m.without_crowd() } else { m })
}

/// The built-in bench avatar as N hand-spawned hierarchies.
fn spawn_builtin(app: &mut App, o: &Options, with_motion: bool) -> usize {
    let (skeleton, vrm) = tassel::builtin::bench_vrm(2, 9, 4);
    let joints = vrm.springs.iter().map(|s| s.joints.len()).sum();
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(skeleton.clone(), Some(vrm)));
    for i in 0..o.n {
        let mut root = app
            .world_mut()
            .spawn((Transform::default(), Sway(0.37 * i as f32)));
        if let Some(m) = motion(&model, o, with_motion) {
            root.insert(m);
        }
        let root = root.id();
        tassel_bevy::spawn_skeleton(app.world_mut(), &skeleton, root);
    }
    joints
}

#[cfg(feature = "gltf")]
fn spawn_file(app: &mut App, o: &Options, name: &str, with_motion: bool) -> Result<usize, String> {
    use bevy::world_serialization::{WorldAssetRoot, WorldSerializationPlugin};
    app.add_plugins((
        bevy::image::ImagePlugin::default(),
        bevy::mesh::MeshPlugin,
        bevy::animation::AnimationPlugin,
        WorldSerializationPlugin,
        bevy::gltf::GltfPlugin::default(),
    ));
    app.register_type::<Visibility>()
        .register_type::<InheritedVisibility>()
        .register_type::<ViewVisibility>()
        .register_type::<Name>()
        .register_type::<Transform>()
        .register_type::<GlobalTransform>()
        .register_type::<bevy::gltf::GltfExtras>()
        .register_type::<bevy::gltf::GltfSceneExtras>()
        .register_type::<ChildOf>()
        .register_type::<Children>()
        .register_type::<bevy::transform::components::TransformTreeChanged>()
        .register_type::<bevy::animation::AnimationTargetId>()
        .register_type::<bevy::animation::AnimatedBy>();
    app.finish();
    app.cleanup();
    let server = app.world().resource::<AssetServer>().clone();
    let model: Handle<TasselModel> = server.load(name.to_string());
    for i in 0..o.n {
        let scene = server.load(GltfAssetLabel::Scene(0).from_asset(name.to_string()));
        let mut e = app.world_mut().spawn((
            WorldAssetRoot(scene),
            Transform::default(),
            Sway(0.37 * i as f32),
        ));
        if let Some(m) = motion(&model, o, with_motion) {
            e.insert(m);
        }
    }
    // The joint count once the file has loaded.
    for _ in 0..3000 {
        app.update();
        if let Some(m) = app.world().resource::<Assets<TasselModel>>().get(&model) {
            return Ok(m
                .vrm()
                .map_or(0, |v| v.springs.iter().map(|s| s.joints.len()).sum()));
        }
        if let bevy::asset::LoadState::Failed(e) = server.load_state(&model) {
            return Err(format!("{name}: {e}"));
        }
    }
    Err(format!("{name}: not loaded after 3000 frames"))
}

#[cfg(not(feature = "gltf"))]
fn spawn_file(_: &mut App, _: &Options, name: &str, _: bool) -> Result<usize, String> {
    Err(format!(
        "{name}: reading a file needs the gltf feature (--features gltf)"
    ))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Runs `frames` updates; returns each update's wall time and the step diagnostics'
/// values (ms): the whole step, its read, solve and write parts.
fn run(app: &mut App, frames: usize) -> (Vec<f64>, [Vec<f64>; 4]) {
    let (mut whole, mut step) = (Vec::new(), <[Vec<f64>; 4]>::default());
    for _ in 0..frames {
        let t = Instant::now();
        app.update();
        whole.push(t.elapsed().as_secs_f64() * 1e3);
        for (path, values) in [STEP_TIME, READ_TIME, SOLVE_TIME, WRITE_TIME]
            .iter()
            .zip(&mut step)
        {
            if let Some(v) = app
                .world()
                .get_resource::<DiagnosticsStore>()
                .and_then(|d| d.get(path))
                .and_then(|d| d.value())
            {
                values.push(v);
            }
        }
    }
    (whole, step)
}

fn main() {
    let o = options().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2);
    });
    let (folder, name) = match &o.file {
        Some(f) => {
            let f = f.canonicalize().unwrap_or_else(|e| {
                eprintln!("error: {}: {e}", f.display());
                std::process::exit(1);
            });
            let folder = f.parent().unwrap().to_string_lossy().into_owned();
            (
                folder,
                Some(f.file_name().unwrap().to_string_lossy().into_owned()),
            )
        }
        None => (".".to_string(), None),
    };
    let mut measured = Vec::new();
    for plugin in [true, false] {
        let mut app = app(&folder, o.threads);
        let joints = match &name {
            Some(name) => spawn_file(&mut app, &o, name, plugin),
            None => Ok(spawn_builtin(&mut app, &o, plugin)),
        }
        .unwrap_or_else(|e| {
            eprintln!("error: {e}");
            std::process::exit(1);
        });
        if plugin {
            // Until every character is bound.
            let bound = |app: &mut App| {
                let w = app.world_mut();
                w.query::<&TasselCharacter>().iter(w).count()
            };
            for _ in 0..3000 {
                app.update();
                if bound(&mut app) == o.n {
                    break;
                }
            }
            let n = bound(&mut app);
            if n != o.n {
                eprintln!("error: {n} of {} characters started", o.n);
                std::process::exit(1);
            }
        }
        run(&mut app, 20);
        let (whole, step) = run(&mut app, o.frames);
        measured.push((
            median(whole),
            step.map(|v| if v.is_empty() { f64::NAN } else { median(v) }),
            joints,
        ));
    }
    let (with, [step, read, solve, write], joints) = measured[0];
    let (without, _, _) = measured[1];
    println!(
        "{} characters x {joints} spring joints, {:?} mode, {}, {} frames, {} compute threads (medians):",
        o.n,
        o.mode,
        if o.own {
            "one CharacterSim each"
        } else {
            "crowd"
        },
        o.frames,
        bevy::tasks::ComputeTaskPool::get().thread_num()
    );
    println!(
        "  plugin step {step:.3} ms per frame, {:.1} ns per joint-step",
        step * 1e6 / (o.n * joints.max(1)) as f64
    );
    println!(
        "  of which: read {read:.3} ms, solve {solve:.3} ms, write {write:.3} ms (medians of each)"
    );
    println!(
        "  whole frame {with:.3} ms with the plugin, {without:.3} ms without ({:.2}x)",
        with / without
    );
}
