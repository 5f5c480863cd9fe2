//! The character controller on a level made from a glTF file's meshes: a capsule dropped
//! on the mesh, then walked across it with collide-and-slide.
//!
//! ```text
//! cargo run --release -p tassel-gltf --example controller [-- level.glb]
//! ```
//! Without a path it uses the sphere mesh of `../shared/testdata/vrm/sphere-collider.gltf`
//! (beside the clone) as the level.

use std::path::PathBuf;
use tassel_gltf::tassel::controller::{CharacterCapsule, ControllerSettings, Level};
use tassel_gltf::tassel::glam::Vec3;
use tassel_gltf::tassel::Transform;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/testdata/vrm/sphere-collider.gltf")
        });
    let model = tassel_gltf::load(&path)?;
    // Every triangle mesh of the file, placed at rest, becomes a collider of the level.
    let level = Level::new(model.meshes.iter().map(|m| m.to_collider()).collect())?;
    let (lo, hi) = (0..level.len())
        .filter_map(|i| level.bounds(i))
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        });
    println!(
        "{}: {} colliders, bounds {lo:.2?} .. {hi:.2?}",
        path.display(),
        level.len()
    );
    // A 1.8 m capsule of radius 0.3 (metres), dropped from above the level's centre.
    let capsule = CharacterCapsule::with_height(1.8, 0.3);
    let settings = ControllerSettings::default();
    let centre = 0.5 * (lo + hi);
    let mut pose = Transform::from_translation(Vec3::new(centre.x, hi.y + 2.0, centre.z));
    let mut velocity = Vec3::ZERO;
    let dt = 1.0 / 60.0;
    for frame in 0..=240 {
        // The caller adds gravity and chooses the walking speed; the controller moves.
        velocity.y = if frame > 0 {
            velocity.y - 9.81 * dt
        } else {
            0.0
        };
        velocity.x = if frame > 90 { 1.5 } else { 0.0 };
        let m = settings.move_shape(&level, &capsule, &pose, velocity * dt, dt)?;
        pose.translation += m.translation;
        if m.grounded {
            velocity.y = 0.0;
        }
        if frame % 30 == 0 {
            println!(
                "t = {:.2} s  centre {:>6.3?}  grounded {}",
                frame as f32 * dt,
                pose.translation,
                m.grounded
            );
        }
    }
    Ok(())
}
