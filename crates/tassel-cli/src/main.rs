//! The `tassel` command: `demo`, `simulate`, `sample`, `inspect`, `bake`, `render`,
//! `plot`, `bench`. Argument parsing, files and printing
//! only; the work is in the `tassel` and `tassel-gltf` crates.

/// `println!` that ignores a closed standard output (`tassel demo | head` must not panic
/// on the broken pipe; the files are already written when the summary is printed).
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout(), $($arg)*);
    }};
}

mod bake;
mod bench;
mod demo;
mod demo_look;
mod inspect;
mod output;
mod plot;
mod progress;
mod render;
mod sample;
mod simulate;
mod subject;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "tassel",
    version,
    about = "Secondary motion for game characters"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Play the embedded character through a small level for 18.5 s (walk up stairs, run
    /// down a ramp, jump a crate, slide along a wall, go through a door that opens and
    /// closes, ride a moving, turning platform) with its hair, tail, skirt, charm and
    /// springs; write demo.glb (the level, the character's skinned body and the baked
    /// animation, door and platform included) and demo.png (eight titled side views in the
    /// level over a chart of the tips' distance from their animated place), demo.rig.toml
    /// (the character's rig) and demo.vrm (the character as a VRM 1.0 avatar: skinned
    /// body, humanoid, its strands as VRM spring bones).
    Demo(demo::Args),
    /// A scripted, machine-readable run: joint positions per frame as JSON.
    Simulate(simulate::Args),
    /// Sampled (and blended) local and world transforms of every node of a file, as JSON.
    Sample(sample::Args),
    /// What a file holds: node tree, skins, clips, VRM springs, joints and colliders,
    /// warnings.
    Inspect(inspect::Args),
    /// Bake secondary motion into a model's clips: play each clip, run the file's VRM
    /// springs and the rig's chains, springs and cloths, write a GLB with the clips keyed.
    Bake(bake::Args),
    /// Pictures of a character's skeleton from the side and the front, simulated bones
    /// highlighted and colliders drawn: a contact sheet (.png) or an animation (.gif).
    Render(render::Args),
    /// A PNG chart of a tip's displacement from the animated pose over time, comparing
    /// modes and frame rates for the same motion.
    Plot(plot::Args),
    /// Measure ns per joint-step for 16 chains × 8 joints with 8 colliders.
    Bench(bench::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Bake(a) => bake::run(a),
        Command::Render(a) => render::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Sample(a) => sample::run(a),
        Command::Inspect(a) => inspect::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}
