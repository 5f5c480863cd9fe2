//! `tassel render` and `tassel plot` end to end: the GIF animates, the contact sheet has
//! the skeleton where it should be, the chart has its lines, bad input writes nothing.

mod common;

use common::{read_png, tassel, testdata, tmp};
use std::path::{Path, PathBuf};

const SIMULATED: [u8; 3] = [235, 110, 30];
const BONE: [u8; 3] = [90, 90, 96];
const BG: [u8; 3] = [250, 250, 248];

fn fox_rig() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/fox.toml")
}

fn run_ok(args: &[&std::ffi::OsStr]) {
    common::run_ok(tassel().args(args));
}

#[test]
fn gif_has_several_different_frames() {
    let dir = tmp("render-gif");
    let out = dir.join("walk.gif");
    run_ok(&[
        "render".as_ref(),
        "--builtin".as_ref(),
        "--clip".as_ref(),
        "walk".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(&out).unwrap()).unwrap();
    let mut frames = Vec::new();
    while let Some(f) = dec.read_next_frame().unwrap() {
        frames.push(f.buffer.to_vec());
    }
    // The walk lasts 1 s: 20 frames per second, both ends included.
    assert_eq!(frames.len(), 21);
    let differing = frames.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(
        differing >= frames.len() / 2,
        "only {differing} frame changes"
    );
    // Every frame shows simulated (orange) bones.
    for (k, f) in frames.iter().enumerate() {
        let orange = f.chunks(4).filter(|p| p[..3] == SIMULATED).count();
        assert!(orange > 50, "frame {k}: {orange} orange pixels");
    }
}

#[test]
fn contact_sheet_draws_the_skeleton_in_every_cell() {
    let Some(fox) = testdata("gltf/Fox.glb") else {
        return;
    };
    let dir = tmp("render-png");
    let out = dir.join("sheet.png");
    run_ok(&[
        "render".as_ref(),
        fox.as_os_str(),
        "--rig".as_ref(),
        fox_rig().as_os_str(),
        "--clip".as_ref(),
        "Walk".as_ref(),
        "--moments".as_ref(),
        "4".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
    ]);
    let (w, h, px) = read_png(&out);
    // The layout the sheet promises: 200-pixel columns, a 44-pixel header, two 240-pixel
    // views (side over front).
    assert_eq!((w, h), (4 * 200, 44 + 2 * 240));
    let at = |x: usize, y: usize| {
        [
            px[(y * w + x) * 3],
            px[(y * w + x) * 3 + 1],
            px[(y * w + x) * 3 + 2],
        ]
    };
    for col in 0..4 {
        for view in 0..2 {
            let (x0, y0) = (col * 200 + 2, 44 + view * 240 + 12);
            let (mut lo, mut hi, mut bone, mut sim) = ((usize::MAX, usize::MAX), (0, 0), 0, 0);
            for y in y0..y0 + 226 {
                for x in x0..x0 + 196 {
                    let c = at(x, y);
                    if c == BONE || c == SIMULATED {
                        lo = (lo.0.min(x), lo.1.min(y));
                        hi = (hi.0.max(x), hi.1.max(y));
                    }
                    bone += (c == BONE) as usize;
                    sim += (c == SIMULATED) as usize;
                }
            }
            assert!(
                bone > 100 && sim > 20,
                "cell {col}/{view}: {bone} bone, {sim} tail pixels"
            );
            // The fox fills its view: the framing leaves a 6 % margin on the tighter side,
            // so the drawing spans most of the cell's width or height.
            let span = ((hi.0 - lo.0) as f32 / 196.0).max((hi.1 - lo.1) as f32 / 226.0);
            assert!(span > 0.6, "cell {col}/{view}: the skeleton spans {span}");
        }
    }
    // Outside the drawing, the background: the bottom-right corner.
    assert_eq!(at(w - 3, h - 3), BG);
}

/// `tassel plot --wind NAME`: the procedural wind's parts (KawaiiPhysics' Wind Scope), one
/// line each, their ranges printed; the strength cycle within the file's range, the
/// constant part the file's; a name that is no procedural wind refused by name.
#[test]
fn plot_draws_a_procedural_winds_parts() {
    let dir = tmp("plot_wind");
    let out = dir.join("wind.png");
    let rig = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../examples/rigs/hair-procedural-wind.toml");
    let run = tassel()
        .args(["plot", "--builtin", "--rig"])
        .arg(&rig)
        .args(["--wind", "breeze", "--duration", "12", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    let range = |name: &str| -> (f32, f32) {
        let at = text
            .find(&format!("{name} "))
            .unwrap_or_else(|| panic!("{text}"));
        let r = text[at + name.len() + 1..]
            .split([',', ')'])
            .next()
            .unwrap();
        let (lo, hi) = r.split_once("..").unwrap();
        (lo.parse().unwrap(), hi.parse().unwrap())
    };
    assert_eq!(range("constant"), (0.15, 0.15), "{text}");
    let (lo, hi) = range("strength cycle");
    // A 6 s cycle over 12 s: it reaches both ends of [0.5, 1.5].
    assert!((lo - 0.5).abs() < 0.01 && (hi - 1.5).abs() < 0.01, "{text}");
    let (lo, hi) = range("sway");
    assert!(
        (lo + 0.1).abs() < 0.005 && (hi - 0.1).abs() < 0.005,
        "{text}"
    );
    let (lo, hi) = range("random");
    assert!(lo < 0.0 && hi > 0.0 && lo >= -0.08 && hi <= 0.08, "{text}");
    let (w, h, _) = read_png(&out);
    assert_eq!((w, h), (900, 480));
    let forces = rig.with_file_name("hair-forces-and-spaces.toml");
    for (file, name, needle) in [
        (&rig, "nothing", "no external force named 'nothing'"),
        (&forces, "breeze", "'breeze' is not a procedural wind"),
    ] {
        let run = tassel()
            .args(["plot", "--builtin", "--rig"])
            .arg(file)
            .args(["--wind", name, "-o"])
            .arg(dir.join("bad.png"))
            .output()
            .unwrap();
        assert!(!run.status.success());
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(needle), "{err}");
        assert!(!dir.join("bad.png").exists());
    }
}

#[test]
fn plot_draws_one_line_per_mode_and_rate() {
    let dir = tmp("plot");
    let out = dir.join("plot.png");
    let run = tassel()
        .args([
            "plot",
            "--builtin",
            "--clip",
            "walk",
            "--modes",
            "fixed,classic",
            "--rates",
            "30,60",
            "-o",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = String::from_utf8_lossy(&run.stdout);
    for name in [
        "fixed 30 hz",
        "fixed 60 hz",
        "classic 30 hz",
        "classic 60 hz",
    ] {
        assert!(text.contains(name), "{text}");
    }
    let (w, h, px) = read_png(&out);
    assert_eq!((w, h), (900, 480));
    // The first four line colours of the chart palette all appear (legend and lines).
    for c in [
        [31u8, 119, 180],
        [230, 85, 13],
        [44, 160, 44],
        [214, 39, 40],
    ] {
        let n = px.chunks(3).filter(|p| *p == c).count();
        assert!(n > 60, "colour {c:?}: {n} pixels");
    }
}

#[test]
fn render_and_plot_bad_input_fail_cleanly() {
    let dir = tmp("render-bad");
    let cases: Vec<(Vec<&str>, &str, &str)> = vec![
        (vec!["render", "--builtin"], "x.jpg", "must end in .png"),
        (
            vec!["render", "--builtin", "--clip", "dance"],
            "x.png",
            "no clip named 'dance'",
        ),
        (vec!["render"], "x.png", "give a FILE or --builtin"),
        (
            vec!["render", "--builtin", "--moments", "0"],
            "x.png",
            "--moments 0",
        ),
        (
            vec!["plot", "--builtin", "--joint", "nose"],
            "x.png",
            "no joint named 'nose'",
        ),
        (
            vec!["plot", "--builtin", "--rates", "0"],
            "x.png",
            "--rates",
        ),
        (
            vec!["plot", "--builtin", "--modes", "spec"],
            "x.png",
            "no VRM springs",
        ),
    ];
    for (args, file, needle) in cases {
        let out = dir.join(file);
        let run = tassel().args(&args).arg("-o").arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(!run.status.success(), "{args:?} succeeded");
        assert!(
            err.contains(needle),
            "{args:?}: {err:?} does not say {needle:?}"
        );
        assert!(
            std::fs::read_dir(&dir).unwrap().next().is_none(),
            "{args:?} left a file"
        );
    }
    let missing = dir.join("no").join("x.gif");
    let run = tassel()
        .args(["render", "--builtin", "-o"])
        .arg(&missing)
        .output()
        .unwrap();
    assert!(!run.status.success());
    assert!(String::from_utf8_lossy(&run.stderr).contains("does not exist"));
}
