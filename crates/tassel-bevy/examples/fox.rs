//! Bevy's Fox walking in a circle, its tail swinging: a rig file's KawaiiPhysics-style
//! chain on a plain glTF.
//!
//! ```text
//! cargo run --release -p tassel-bevy --features examples --example fox
//! ```
//! Reads `../shared/testdata/gltf/Fox.glb` (beside the clone) and
//! `examples/rigs/fox.toml`. Keys: R resets the tail, G shows or hides the colliders.

use bevy::asset::io::AssetSourceBuilder;
use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use bevy::world_serialization::WorldInstanceReady;
use std::path::PathBuf;
use tassel_bevy::prelude::*;

const FOX: &str = "testdata://gltf/Fox.glb";

fn main() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let testdata = root.join("../shared/testdata");
    if !testdata.join("gltf/Fox.glb").is_file() {
        eprintln!(
            "error: {} is missing: the example needs ../shared beside the clone",
            testdata.join("gltf/Fox.glb").display()
        );
        std::process::exit(1);
    }
    App::new()
        .register_asset_source(
            "testdata",
            AssetSourceBuilder::platform_default(&testdata.to_string_lossy(), None),
        )
        .add_plugins(DefaultPlugins.set(AssetPlugin {
            file_path: root.to_string_lossy().into_owned(),
            ..default()
        }))
        .add_plugins((TasselPlugin, TasselGizmosPlugin))
        .add_systems(Startup, setup)
        .add_systems(Update, (walk_in_a_circle, keys).before(TasselSystems::Step))
        .run();
}

#[derive(Component)]
struct Walk(Handle<AnimationGraph>, AnimationNodeIndex);

fn setup(
    mut commands: Commands,
    assets: Res<AssetServer>,
    mut graphs: ResMut<Assets<AnimationGraph>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<StandardMaterial>>,
) {
    // Fox.glb's animations: 0 survey, 1 walk, 2 run.
    let (graph, walk) =
        AnimationGraph::from_clip(assets.load(GltfAssetLabel::Animation(1).from_asset(FOX)));
    commands
        .spawn((
            WorldAssetRoot(assets.load(GltfAssetLabel::Scene(0).from_asset(FOX))),
            // Its own sim (not a crowd of one) so that the gizmos can draw its chain.
            SecondaryMotion::new(assets.load(FOX))
                .with_rig(assets.load("examples/rigs/fox.toml"))
                .without_crowd(),
            Walk(graphs.add(graph), walk),
            Transform::default(),
        ))
        .observe(play_walk);
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(0.0, 220.0, 420.0).looking_at(Vec3::new(0.0, 20.0, 0.0), Vec3::Y),
    ));
    commands.spawn((
        Mesh3d(meshes.add(Plane3d::default().mesh().size(2000.0, 2000.0))),
        MeshMaterial3d(materials.add(Color::srgb(0.3, 0.5, 0.3))),
    ));
    commands.spawn((
        DirectionalLight::default(),
        Transform::from_xyz(100.0, 300.0, 200.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    info!("R: reset the tail, G: colliders");
}

fn play_walk(
    ready: On<WorldInstanceReady>,
    mut commands: Commands,
    children: Query<&Children>,
    walks: Query<&Walk>,
    mut players: Query<&mut AnimationPlayer>,
) {
    let Ok(walk) = walks.get(ready.entity) else {
        return;
    };
    for child in children.iter_descendants(ready.entity) {
        if let Ok(mut player) = players.get_mut(child) {
            player.play(walk.1).repeat();
            commands
                .entity(child)
                .insert(AnimationGraphHandle(walk.0.clone()));
        }
    }
}

/// A circle of 150 units at the walk's pace, facing along it.
fn walk_in_a_circle(time: Res<Time>, mut q: Query<&mut Transform, With<Walk>>) {
    let a = 0.35 * time.elapsed_secs();
    for mut t in &mut q {
        t.translation = Vec3::new(150.0 * a.cos(), 0.0, -150.0 * a.sin());
        t.rotation = Quat::from_rotation_y(a + std::f32::consts::PI);
    }
}

fn keys(
    input: Res<ButtonInput<KeyCode>>,
    mut characters: Query<&mut TasselCharacter>,
    mut store: ResMut<GizmoConfigStore>,
) {
    if input.just_pressed(KeyCode::KeyR) {
        for mut c in &mut characters {
            c.reset();
        }
    }
    if input.just_pressed(KeyCode::KeyG) {
        let (config, _) = store.config_mut::<DefaultGizmoConfigGroup>();
        config.enabled = !config.enabled;
    }
}
