//! A rope of 20 particles pinned at both ends settles into a catenary; prints the sag at
//! mid-span next to the closed form `a·(cosh(S/2a) − 1)` with `L = 2a·sinh(S/2a)`.
//!
//! Run: `cargo run --release -p tassel --example rope`

use glam::Vec3;
use tassel::dynamics::particles::{ParticleSettings, ParticleWorld};

fn main() -> Result<(), tassel::Error> {
    let (span, length, n) = (1.6_f32, 2.0_f32, 20);
    let mut world = ParticleWorld::new(ParticleSettings {
        iterations: 120,
        damping: 0.03,
        ..Default::default()
    });
    let rope = world.add_rope(Vec3::ZERO, Vec3::new(length, 0.0, 0.0), n, 1.0);
    world.pin(rope[0], Vec3::ZERO)?;
    world.pin(rope[n - 1], Vec3::new(span, 0.0, 0.0))?;
    println!("rope: {n} particles, length {length} m, ends {span} m apart");
    for second in 1..=10 {
        for _ in 0..60 {
            world.step(1.0 / 60.0)?;
        }
        let mid = 0.5 * (world.position(rope[n / 2 - 1]) + world.position(rope[n / 2]));
        println!("t = {second:2} s  mid-span sag {:.4} m", -mid.y);
    }
    // Closed form: solve L = 2a·sinh(S/2a) for a by bisection.
    let (s, l) = (span as f64, length as f64);
    let (mut lo, mut hi) = (1e-3_f64, 1e3_f64);
    for _ in 0..200 {
        let a = 0.5 * (lo + hi);
        if 2.0 * a * (s / (2.0 * a)).sinh() > l {
            lo = a;
        } else {
            hi = a;
        }
    }
    let a = 0.5 * (lo + hi);
    println!(
        "catenary: a = {a:.4} m, closed-form sag {:.4} m",
        a * ((s / (2.0 * a)).cosh() - 1.0)
    );
    for (k, &i) in rope.iter().enumerate().step_by(3) {
        let p = world.position(i);
        println!("  particle {k:2}: x {:.3}  y {:.3}", p.x, p.y);
    }
    Ok(())
}
