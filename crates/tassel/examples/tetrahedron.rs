//! A tetrahedron of four particles and six sticks dropped on the ground: prints its
//! lowest corner and its worst edge-length error while it falls, bounces and settles.
//!
//! Run: `cargo run --release -p tassel --example tetrahedron`

use glam::{Quat, Vec3};
use tassel::dynamics::particles::{ParticleSettings, ParticleWorld};

fn main() -> Result<(), tassel::Error> {
    let edge = 0.5;
    let mut world = ParticleWorld::new(ParticleSettings {
        friction: 0.5,
        ..Default::default()
    });
    let ids = world.add_tetrahedron(
        Vec3::new(0.0, 1.5, 0.0),
        edge,
        Quat::from_rotation_z(0.4) * Quat::from_rotation_x(0.3),
        1.0,
    );
    world.add_ground(0.0);
    println!("tetrahedron, edge {edge} m, dropped from 1.5 m onto y = 0");
    let mut worst = 0.0_f32;
    for frame in 1..=120 {
        world.step(1.0 / 60.0)?;
        let mut frame_worst = 0.0_f32;
        for i in 0..4 {
            for j in i + 1..4 {
                let l = (world.position(ids[i]) - world.position(ids[j])).length();
                frame_worst = frame_worst.max((l - edge).abs() / edge);
            }
        }
        worst = worst.max(frame_worst);
        if frame % 10 == 0 {
            let lowest = ids
                .iter()
                .map(|&i| world.position(i).y)
                .fold(f32::MAX, f32::min);
            println!(
                "t = {:.2} s  lowest corner y {lowest:+.4} m  edge error {:.3} %",
                frame as f32 / 60.0,
                100.0 * frame_worst
            );
        }
    }
    println!("worst edge error over the run: {:.3} %", 100.0 * worst);
    Ok(())
}
