//! A VRM file's spring bones, swaying: load the file, make a character, run frames, read
//! where the spring tails are (world space, by bone).
//!
//! ```text
//! cargo run --release -p tassel-gltf --example vrm_springs [-- avatar.vrm]
//! ```
//! Without a path it reads `../shared/testdata/vrm/smoke_spring.vrm` (beside the clone).

use std::path::PathBuf;
use tassel_gltf::tassel::dynamics::{RigSettings, SimMode};
use tassel_gltf::tassel::glam::{Quat, Vec3};
use tassel_gltf::tassel::{CharacterSim, Transform};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("../../../shared/testdata/vrm/smoke_spring.vrm")
        });
    let model = tassel_gltf::load(&path)?;
    let vrm = model
        .vrm
        .as_ref()
        .ok_or_else(|| format!("{}: no VRM spring bones", path.display()))?;
    // `fixed` steps at 60 Hz inside whatever the frame rate is (the look does not change
    // with it); `spec` steps once per frame as the VRM specification does.
    let mut rig = RigSettings::default();
    let (_, options) = SimMode::apply(Some(SimMode::Fixed), &mut rig, true)?;
    let mut sim = CharacterSim::with_vrm(model.skeleton.clone(), &rig, &vrm.springs, options)?;
    println!(
        "{}: VRM {:?}, {} springs, {} bones simulated",
        path.display(),
        vrm.version,
        vrm.springs.springs.len(),
        sim.simulated_joints().len()
    );
    // No clip: the rest pose, with the avatar swaying and turning. The first frame takes
    // dt = 0 (it places the springs on the pose); then the frame time.
    let rest = model.skeleton.rest().to_vec();
    let fps = 60.0;
    for frame in 0..=120 {
        let t = frame as f32 / fps;
        let at = Transform::from_translation_rotation(
            Vec3::new(0.3 * (4.0 * t).sin(), 0.0, 0.0),
            Quat::from_rotation_y(0.5 * (2.5 * t).sin()),
        );
        sim.frame(&rest, at, if frame == 0 { 0.0 } else { 1.0 / fps })?;
        if frame % 30 == 0 {
            println!("t = {t:.2} s");
            for &j in sim.simulated_joints() {
                if let Some(tail) = sim.vrm_tail_world(j) {
                    println!("  {:<24} tail at {:>7.3?}", sim.skeleton().name(j), tail);
                }
            }
        }
    }
    Ok(())
}
