//! A flag on a pole in gusty wind: a 9 × 6 cloth grid (with shear sticks) whose pole edge
//! is pinned. Prints, once a second, how far the free edge streams downwind and how much
//! it droops; with gusts it flutters but stays downwind and on its full width.
//!
//! Run: `cargo run --release -p tassel --example flag`

use glam::Vec3;
use tassel::dynamics::particles::{ParticleSettings, ParticleWorld};

fn main() -> Result<(), tassel::Error> {
    let (nx, ny) = (9, 6);
    let (width, height) = (0.9_f32, 0.6_f32);
    let mut world = ParticleWorld::new(ParticleSettings {
        wind: Vec3::new(12.0, 0.0, 2.0),
        gust: 0.6,
        seed: 42,
        damping: 0.02,
        iterations: 16,
        ..Default::default()
    });
    // The flag starts hanging flat against the pole plane, across the wind.
    let top = Vec3::new(0.0, 2.0, 0.0);
    let ids = world.add_cloth(
        top,
        Vec3::new(0.0, 0.0, width),
        Vec3::new(0.0, -height, 0.0),
        [nx, ny],
        true,
        0.2,
    );
    for y in 0..ny {
        let i = ids[y * nx];
        world.pin(i, world.position(i))?;
    }
    world.add_ground(0.0);
    println!("flag {width} m × {height} m on a pole, wind (12, 0, 2) m/s² with 60 % gusts");
    for second in 1..=8 {
        for _ in 0..60 {
            world.step(1.0 / 60.0)?;
        }
        let free: Vec<Vec3> = (0..ny)
            .map(|y| world.position(ids[y * nx + nx - 1]))
            .collect();
        let downwind = free.iter().map(|p| p.x).sum::<f32>() / ny as f32;
        let pole_top = world.position(ids[0]);
        let edge_top = free[0];
        println!(
            "t = {second} s  free edge {downwind:.3} m downwind, top corner {:.3} m from the pole top, droop {:.3} m",
            (edge_top - pole_top).length(),
            pole_top.y - edge_top.y,
        );
    }
    Ok(())
}
