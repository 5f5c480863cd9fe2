//! A VRM avatar swaying, its spring bones (0.x or 1.0) run by Tassel.
//!
//! ```text
//! cargo run --release -p tassel-bevy --features examples --example vrm [-- path/to/avatar.vrm]
//! ```
//! Without a path it opens `../shared/testdata/vrm/smoke_spring.vrm` (beside the clone).
//! The avatar faces the camera whatever its VRM version (0.x models face −Z, 1.0 models
//! +Z). Keys: M switches fixed / spec stepping, R resets the springs, T teleports the
//! avatar 1.5 m to the side and back (the springs start again there, no whip; the camera
//! follows), G shows or hides the colliders.

use bevy::asset::AssetPlugin;
use bevy::prelude::*;
use std::path::PathBuf;
use tassel_bevy::prelude::*;

fn main() {
    let file = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/testdata/vrm/smoke_spring.vrm")
        });
    let file = file.canonicalize().unwrap_or_else(|e| {
        eprintln!("error: {}: {e}", file.display());
        std::process::exit(1);
    });
    let folder = file.parent().unwrap().to_string_lossy().into_owned();
    let name = file.file_name().unwrap().to_string_lossy().into_owned();
    let face = facing(&file);
    App::new()
        .add_plugins(DefaultPlugins.set(AssetPlugin {
            file_path: folder,
            ..default()
        }))
        .add_plugins((TasselPlugin, TasselGizmosPlugin))
        .insert_resource(Avatar(name, face))
        .add_systems(Startup, setup)
        .add_systems(Update, (sway, keys, follow).before(TasselSystems::Step))
        .add_systems(Update, report_errors)
        .run();
}

/// The file's name and the turn that makes it face +Z (the camera).
#[derive(Resource)]
struct Avatar(String, Quat);

/// VRM 0.x models face −Z, VRM 1.0 and plain glTF +Z: a 0.x file (its JSON names the
/// `VRM` extension, not `VRMC_vrm`) is turned half round.
fn facing(file: &std::path::Path) -> Quat {
    let bytes = std::fs::read(file).unwrap_or_default();
    let has = |s: &[u8]| bytes.windows(s.len()).any(|w| w == s);
    if !has(b"\"VRMC_vrm\"") && has(b"\"VRM\"") {
        Quat::from_rotation_y(std::f32::consts::PI)
    } else {
        Quat::IDENTITY
    }
}

#[derive(Component)]
struct Sway {
    offset: Vec3,
    face: Quat,
}

fn setup(mut commands: Commands, assets: Res<AssetServer>, avatar: Res<Avatar>) {
    commands.spawn((
        WorldAssetRoot(assets.load(GltfAssetLabel::Scene(0).from_asset(avatar.0.clone()))),
        // Its own sim (not a crowd of one) so that the gizmos can draw its springs.
        SecondaryMotion::new(assets.load(avatar.0.clone())).without_crowd(),
        Transform::from_rotation(avatar.1),
        Sway {
            offset: Vec3::ZERO,
            face: avatar.1,
        },
    ));
    commands.spawn((
        Camera3d::default(),
        Transform::from_xyz(0.0, 1.3, 2.6).looking_at(Vec3::new(0.0, 1.0, 0.0), Vec3::Y),
    ));
    commands.spawn((
        DirectionalLight::default(),
        Transform::from_xyz(2.0, 4.0, 3.0).looking_at(Vec3::ZERO, Vec3::Y),
    ));
    info!("M: fixed/spec stepping, R: reset, T: teleport 1.5 m, G: colliders");
}

/// Side to side and a turn, so the hair swings.
fn sway(time: Res<Time>, mut q: Query<(&Sway, &mut Transform)>) {
    let t = time.elapsed_secs();
    for (sway, mut transform) in &mut q {
        transform.translation = sway.offset + Vec3::new(0.35 * (2.2 * t).sin(), 0.0, 0.0);
        transform.rotation = sway.face * Quat::from_rotation_y(0.6 * (1.3 * t).sin());
    }
}

/// The camera keeps the avatar in view after a teleport.
fn follow(avatar: Query<&Sway>, mut camera: Query<&mut Transform, With<Camera3d>>) {
    let (Ok(sway), Ok(mut camera)) = (avatar.single(), camera.single_mut()) else {
        return;
    };
    *camera = Transform::from_xyz(sway.offset.x, 1.3, 2.6)
        .looking_at(Vec3::new(sway.offset.x, 1.0, 0.0), Vec3::Y);
}

fn keys(
    input: Res<ButtonInput<KeyCode>>,
    mut motions: Query<(
        &mut SecondaryMotion,
        Option<&mut TasselCharacter>,
        &mut Sway,
    )>,
    mut store: ResMut<GizmoConfigStore>,
    mut window: Query<&mut Window>,
) {
    for (mut motion, character, mut sway) in &mut motions {
        if input.just_pressed(KeyCode::KeyM) {
            motion.mode = match motion.mode {
                SimMode::Fixed => SimMode::Spec,
                _ => SimMode::Fixed,
            };
        }
        if let Some(mut character) = character {
            if input.just_pressed(KeyCode::KeyR) {
                character.reset();
            }
            if input.just_pressed(KeyCode::KeyT) {
                sway.offset.x = if sway.offset.x == 0.0 { 1.5 } else { 0.0 };
                character.teleport();
            }
        }
        if let Ok(mut w) = window.single_mut() {
            w.title = format!("tassel-bevy vrm: {} stepping", motion.mode.name());
        }
    }
    if input.just_pressed(KeyCode::KeyG) {
        let (config, _) = store.config_mut::<DefaultGizmoConfigGroup>();
        config.enabled = !config.enabled;
    }
}

fn report_errors(mut errors: MessageReader<TasselError>) {
    for e in errors.read() {
        eprintln!("tassel: {}", e.message);
    }
}
