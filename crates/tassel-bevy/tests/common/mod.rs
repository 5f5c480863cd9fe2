//! Shared set-up of the plugin tests: a headless app (no window, no GPU) stepping by a
//! fixed duration, and a hand-spawned bone hierarchy.

#![allow(dead_code)]

use bevy::app::AnimationSystems;
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use std::time::Duration;
use tassel::anim::Clip;
use tassel_bevy::prelude::*;

/// `../shared/testdata` from the repository root, or `None` (with a message) when the
/// folder is missing and `TASSEL_REQUIRE_TESTDATA` is not set.
pub fn testdata() -> Option<std::path::PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/testdata");
    if root.is_dir() {
        return Some(root.canonicalize().unwrap());
    }
    if std::env::var_os("TASSEL_REQUIRE_TESTDATA").is_some() {
        panic!("../shared/testdata is missing (TASSEL_REQUIRE_TESTDATA is set)");
    }
    eprintln!("SKIPPED: ../shared/testdata is missing beside the repository");
    None
}

/// A headless app at `hz` frames per second (each `update` advances `Time` by 1/hz).
pub fn app(hz: f64) -> App {
    app_with_assets(hz, "assets")
}

/// The same, reading files from `folder`.
pub fn app_with_assets(hz: f64, folder: &str) -> App {
    build_app(hz, folder, None)
}

/// A headless app at `hz` whose compute task pool (where the plugin reads and steps its
/// crowds) has `threads` threads. Bevy's pools are made once per process: the first app
/// of a process decides.
pub fn app_on_threads(hz: f64, threads: usize) -> App {
    build_app(hz, "assets", Some(threads))
}

fn build_app(hz: f64, folder: &str, threads: Option<usize>) -> App {
    let mut tasks = bevy::app::TaskPoolPlugin::default();
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
        TasselPlugin,
    ))
    .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / hz,
    )))
    .init_resource::<Errors>()
    .add_systems(Last, collect_errors);
    app
}

/// Every [`TasselError`] seen.
#[derive(Resource, Default)]
pub struct Errors(pub Vec<TasselError>);

fn collect_errors(mut messages: MessageReader<TasselError>, mut errors: ResMut<Errors>) {
    errors.0.extend(messages.read().cloned());
}

/// Marks the entity of skeleton joint `.0`.
#[derive(Component)]
pub struct Bone(pub usize);

/// Spawns `skeleton` at rest under `root` ([`tassel_bevy::spawn_skeleton`]), each joint's
/// entity marked with its [`Bone`]; returns the joints' entities.
pub fn spawn_skeleton(world: &mut World, skeleton: &tassel::Skeleton, root: Entity) -> Vec<Entity> {
    let entities = tassel_bevy::spawn_skeleton(world, skeleton, root);
    for (j, &e) in entities.iter().enumerate() {
        world.entity_mut(e).insert(Bone(j));
    }
    entities
}

/// Tassel's transform as Bevy's.
pub fn bevy_transform(t: &tassel::Transform) -> Transform {
    Transform {
        translation: t.translation,
        rotation: t.rotation,
        scale: t.scale,
    }
}

/// The animated pose the test animation gives at `t` seconds (the clip looped over rest).
pub fn animated(skeleton: &tassel::Skeleton, clip: &Clip, t: f32) -> Vec<tassel::Transform> {
    let mut locals = skeleton.rest().to_vec();
    clip.sample_looped(t, &mut locals);
    locals
}

/// Where the test moves the character at `t` seconds: a sway along X and a turn.
pub fn path(t: f64) -> tassel::Transform {
    tassel::Transform::new(
        Vec3::new((0.3 * (std::f64::consts::TAU * t).sin()) as f32, 0.1, 2.0),
        Quat::from_rotation_y((0.5 * (std::f64::consts::TAU * 0.7 * t).sin()) as f32),
        Vec3::ONE,
    )
}

/// The test's animation, as a game would have it.
#[derive(Resource)]
pub struct TestMotion {
    /// The skeleton the clip animates.
    pub skeleton: tassel::Skeleton,
    /// The clip, looped.
    pub clip: Clip,
    /// The entity moved along [`path`].
    pub character: Entity,
    /// Play the clip (else the bones stay at rest).
    pub animate: bool,
}

/// Moves the character (in `Update`) and animates its bones (in Bevy's
/// `AnimationSystems`, as an `AnimationPlayer` would) by this frame's time.
pub fn add_test_motion(app: &mut App, motion: TestMotion) {
    app.insert_resource(motion)
        .add_systems(Update, move_character)
        .add_systems(PostUpdate, animate_bones.in_set(AnimationSystems));
}

fn move_character(time: Res<Time>, motion: Res<TestMotion>, mut q: Query<&mut Transform>) {
    if let Ok(mut t) = q.get_mut(motion.character) {
        *t = bevy_transform(&path(time.elapsed_secs_f64()));
    }
}

fn animate_bones(time: Res<Time>, motion: Res<TestMotion>, mut q: Query<(&Bone, &mut Transform)>) {
    if !motion.animate {
        return;
    }
    let locals = animated(&motion.skeleton, &motion.clip, time.elapsed_secs());
    for (bone, mut t) in &mut q {
        *t = bevy_transform(&locals[bone.0]);
    }
}

/// Runs `update` until `done` or `frames` updates, sleeping a little between (asset loads
/// run on other threads).
pub fn update_until(app: &mut App, frames: usize, mut done: impl FnMut(&mut App) -> bool) -> bool {
    for _ in 0..frames {
        app.update();
        if done(app) {
            return true;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    false
}
