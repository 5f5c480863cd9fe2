//! Hello, Tassel: take the embedded character, blend two of its clips, move it, simulate
//! its chains and print where the ponytail's tip is.
//!
//! Run: `cargo run --release -p tassel --example hello`

use glam::{Quat, Vec3};
use tassel::{builtin, CharacterSim, Transform};

fn main() -> Result<(), tassel::Error> {
    // 1. A character: skeleton, rig (chains + colliders) and clips. Your own comes from a
    //    glTF file (tassel-gltf) and a rig file (RigSettings::from_toml_str).
    let character = builtin::character();
    let skeleton = &character.skeleton;
    let mut sim = CharacterSim::new(skeleton.clone(), &character.rig)?;

    let walk = &character.clips[builtin::clip::WALK];
    let run = &character.clips[builtin::clip::RUN];
    let mut a = skeleton.rest().to_vec();
    let mut b = skeleton.rest().to_vec();
    let mut blended = skeleton.rest().to_vec();
    let tip = skeleton
        .find("ponytail_5")
        .expect("the built-in character has a ponytail");

    let dt = 1.0 / 60.0;
    for frame in 0..120 {
        let t = frame as f32 * dt;
        // 2. Sample two clips at the same phase and blend them 70 / 30.
        walk.sample_looped(t / run.duration * walk.duration, &mut a);
        run.sample_looped(t, &mut b);
        tassel::anim::blend_locals(&a, &b, 0.3, &mut blended);

        // 3. Move the character (here: 2.5 m/s forward, turning slowly). A game would get
        //    this transform from its character controller.
        let component = Transform::from_translation_rotation(
            Vec3::new(0.0, 0.0, 2.5 * t),
            Quat::from_rotation_y(0.3 * t),
        );

        // 4. Simulate: the returned pose has the chains' rotations written back.
        let pose = sim.frame(&blended, component, dt)?;
        if frame % 30 == 0 {
            let world = component.transform_point(pose.models[tip].translation);
            let animated = component.transform_point(sim.animated_models()[tip].translation);
            println!(
                "t = {t:.2} s: ponytail tip at {world:.3}, {:.3} m from where the animation alone puts it",
                (world - animated).length()
            );
        }
    }
    Ok(())
}
