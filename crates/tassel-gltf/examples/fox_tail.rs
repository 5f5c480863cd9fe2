//! Khronos' Fox with a rig file: its walk clip played, the tail chain swinging, the tail
//! tip read by the chain's name.
//!
//! ```text
//! cargo run --release -p tassel-gltf --example fox_tail
//! ```
//! Reads `../shared/testdata/gltf/Fox.glb` (beside the clone) and `examples/rigs/fox.toml`.

use std::path::Path;
use tassel_gltf::tassel::dynamics::RigSettings;
use tassel_gltf::tassel::glam::Vec3;
use tassel_gltf::tassel::{CharacterSim, Transform};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let model = tassel_gltf::load(&root.join("../shared/testdata/gltf/Fox.glb"))?;
    let rig = RigSettings::from_toml_str(&std::fs::read_to_string(
        root.join("examples/rigs/fox.toml"),
    )?)?;
    let mut sim = CharacterSim::new(model.skeleton.clone(), &rig)?;
    let walk = model
        .clip("Walk")
        .ok_or("Fox.glb has no clip called Walk")?;
    // The fox walks forward (+Z, in its centimetre-sized units) at about 60 units/s.
    let fps = 30.0;
    let mut locals = model.skeleton.rest().to_vec();
    for frame in 0..=90 {
        let t = frame as f32 / fps;
        locals.copy_from_slice(model.skeleton.rest());
        walk.sample_looped(t, &mut locals);
        let at = Transform::from_translation(Vec3::new(0.0, 0.0, 60.0 * t));
        sim.frame(&locals, at, if frame == 0 { 0.0 } else { 1.0 / fps })?;
        if frame % 15 == 0 {
            let tip = sim.chain_tip_world("tail").ok_or("no chain called tail")?;
            let hip = sim
                .bone_world_by_name("b_Hip_01")
                .ok_or("no bone b_Hip_01")?;
            println!(
                "t = {t:.2} s  hips at {:>7.1?}  tail tip at {:>7.1?}",
                hip.translation, tip
            );
        }
    }
    Ok(())
}
