//! `tassel render`: the skeleton seen from the side and the front while a clip plays,
//! as a contact sheet (.png) or an animation (.gif).

use crate::output::{check_output_dir, write_atomic};
use crate::subject::Mode;
use crate::subject::{SubjectArgs, SwayArgs};
use std::path::PathBuf;
use tassel_gltf::{key_times, play, BakeOptions};
use tassel_render::{animation_frames, contact_sheet, encode_gif, Figure};

/// Options of `tassel render`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    subject: SubjectArgs,
    /// spec, fixed or classic (as for `simulate`).
    #[arg(long, value_enum)]
    mode: Option<Mode>,
    /// Seconds the clip plays, looped, before the pictures start.
    #[arg(long, default_value_t = 1.0)]
    warmup: f32,
    #[command(flatten)]
    sway: SwayArgs,
    /// Seconds shown for the rest pose of a file without clips.
    #[arg(long, default_value_t = 2.0)]
    duration: f32,
    /// PNG: how many moments the contact sheet shows.
    #[arg(long, default_value_t = 6)]
    moments: usize,
    /// GIF: frames per second of the animation (the simulation runs at 60).
    #[arg(long, default_value_t = 20.0)]
    gif_fps: f32,
    /// Output: .png (contact sheet) or .gif (animation).
    #[arg(short, long)]
    out: PathBuf,
}

const SIM_FPS: f32 = 60.0;

/// The most frames one GIF may hold (each is a whole picture in memory until encoded).
const MAX_GIF_FRAMES: usize = 1_000;

pub fn run(a: Args) -> Result<(), String> {
    let ext = a
        .out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let gif = match ext.as_str() {
        "gif" => true,
        "png" => false,
        _ => {
            return Err(format!(
                "{}: the output must end in .png (contact sheet) or .gif (animation)",
                a.out.display()
            ))
        }
    };
    if !(1..=24).contains(&a.moments) {
        return Err(format!("--moments {} must be 1..=24", a.moments));
    }
    if !(a.gif_fps.is_finite() && a.gif_fps >= 1.0 && a.gif_fps <= SIM_FPS) {
        return Err(format!("--gif-fps {} must be in 1..=60", a.gif_fps));
    }
    check_output_dir(&a.out)?;
    let (subject, clip) = a.subject.load()?;
    let clip = clip.map(|i| &subject.clips[i]);
    let (mut sim, mode) = subject.sim(a.mode)?;
    let options = BakeOptions {
        fps: SIM_FPS,
        warmup: a.warmup,
        rest_duration: a.duration,
        sway: a.sway.sway(),
    };
    options.validate().map_err(|e| e.to_string())?;
    let duration = clip.map(|c| c.duration).unwrap_or(a.duration);
    let times = key_times(duration, SIM_FPS);
    let n = times.len();
    // Which simulated frames become pictures.
    let picked: Vec<usize> = if gif {
        let step = SIM_FPS / a.gif_fps;
        let count = ((n - 1) as f32 / step).floor() as usize + 1;
        (0..count)
            .map(|k| ((k as f32 * step).round() as usize).min(n - 1))
            .collect()
    } else if a.moments == 1 || n == 1 {
        vec![0]
    } else {
        (0..a.moments)
            .map(|k| k * (n - 1) / (a.moments - 1))
            .collect()
    };
    if picked.len() > MAX_GIF_FRAMES {
        return Err(format!(
            "the clip lasts {duration} s: {} frames at {} fps is more than the limit of \
             {MAX_GIF_FRAMES} GIF frames; lower --gif-fps or write a .png",
            picked.len(),
            a.gif_fps
        ));
    }
    let mut figures = Vec::with_capacity(picked.len());
    play(&mut sim, clip, &times, &options, &mut |f| {
        for _ in picked.iter().filter(|&&p| p == f.index) {
            figures.push(Figure::from_sim(f.sim, &f.component, f.time));
        }
        Ok::<(), String>(())
    })
    .map_err(|e| e.to_string())?;
    let clip_name = clip.map(|c| c.name.as_str()).unwrap_or("REST");
    let title = format!("{} - {} - {}", subject.name, clip_name, mode.name());
    let bytes = if gif {
        if figures.len() < 2 {
            return Err(format!(
                "the clip lasts {duration} s: too short for an animation at {} fps; write a .png",
                a.gif_fps
            ));
        }
        let delay = (100.0 / a.gif_fps).round() as u16;
        encode_gif(&animation_frames(&figures, &title), delay).map_err(|e| e.to_string())?
    } else {
        contact_sheet(&figures, &title)
            .png()
            .map_err(|e| e.to_string())?
    };
    write_atomic(&a.out, &bytes)?;
    say!(
        "wrote {} ({} {}, {} simulated bone(s), mode {})",
        a.out.display(),
        figures.len(),
        if gif { "frames" } else { "moments" },
        sim.simulated_joints().len(),
        mode.name()
    );
    Ok(())
}
