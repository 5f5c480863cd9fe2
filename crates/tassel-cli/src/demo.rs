//! `tassel demo`: the embedded character through the scripted sequence.

use crate::output::write_atomic;
use glam::{Quat, Vec3};
use std::path::PathBuf;
use std::time::Instant;
use tassel::builtin::level::LevelRun;
use tassel::builtin::{self, DemoScript};
use tassel::collide::Shape;
use tassel::dynamics::cloth::ConstraintKind;
use tassel::CharacterSim;
use tassel_gltf::{export_glb, BakedClip, BakedTrack, BoneMesh, ExportSource};
use tassel_render::{draw_strip, Panel, Series};

/// Options of `tassel demo`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder for demo.glb and demo.png.
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Frames per second.
    #[arg(long, default_value_t = 60.0)]
    fps: f32,
}

const MOMENTS: [f32; 6] = [1.0, 4.9, 6.2, 7.3, 9.6, 11.2];

fn chain_color(name: &str) -> [u8; 3] {
    match name.split('_').next().unwrap_or("") {
        "ponytail" => [235, 120, 20],
        "lock" => [210, 170, 0],
        "tail" => [40, 90, 220],
        "skirt" => [200, 40, 160],
        "charm" => [0, 160, 140],
        "chest" => [220, 30, 30],
        _ => [0, 0, 0],
    }
}

pub fn run(a: Args) -> Result<(), String> {
    if !(a.fps.is_finite() && (1.0..=1000.0).contains(&a.fps)) {
        return Err(format!("--fps {} must be 1..=1000", a.fps));
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let c = builtin::character();
    let sk = &c.skeleton;
    let mut sim = CharacterSim::new(sk.clone(), &c.rig).map_err(|e| e.to_string())?;
    let mut run = LevelRun::new().map_err(|e| e.to_string())?;
    // One world for the controller and the secondary motion (the skirt and the charm
    // collide with it).
    sim.set_level(Some(run.level.clone()));
    let dt = 1.0 / a.fps;
    let frames = (LevelRun::DURATION * a.fps).round() as usize;
    let mut locals = sk.rest().to_vec();
    let mut animator = DemoScript.animator(&c);
    let (mut grounded, mut stepped, mut snapped, mut sliding, mut wall) = (0, 0, 0, 0, 0);
    let mut move_time = 0.0f64;
    let mut end = Vec3::ZERO;
    let mut visited: Vec<String> = Vec::new();
    let mut events = 0usize;
    let n = sk.len();
    let mut rot_keys: Vec<Vec<Quat>> = vec![Vec::with_capacity(frames + 1); n];
    let mut tr_keys: Vec<Vec<Vec3>> = vec![Vec::with_capacity(frames + 1); n];
    let mut times = Vec::with_capacity(frames + 1);
    // Solver membership per joint (chain or cloth name), for colours.
    let mut group_of: Vec<Option<String>> = vec![None; n];
    for p in 0..sim.chains().point_count() {
        let info = sim.chains().point(p);
        if let (Some(j), Some(_)) = (info.joint, info.parent) {
            group_of[j] = Some(sim.chains().chain_settings(info.chain).name.clone());
        }
    }
    for ci in 0..sim.cloths().cloth_count() {
        let name = &sim.cloths().settings(ci).name;
        for ch in sim.cloths().chains(ci) {
            for p in ch.clone() {
                if let Some(j) = sim.cloths().joint(p) {
                    if !sim.cloths().is_fixed(p) {
                        group_of[j] = Some(name.clone());
                    }
                }
            }
        }
    }
    for ri in 0..sim.ropes().len() {
        let name = sim.ropes().settings(ri).name.clone();
        for j in sim.ropes().simulated_joints() {
            group_of[j].get_or_insert_with(|| name.clone());
        }
    }
    // Tips whose distance from their animated place is plotted: chains by name, and the
    // skirt cloth's first chain.
    let tracked = ["ponytail", "tail", "skirt", "lock_l"];
    let chain_tips: Vec<Option<usize>> = tracked
        .iter()
        .map(|name| {
            (0..sim.chains().chain_count())
                .find(|&i| sim.chains().chain_settings(i).name == *name)
                .map(|ci| sim.chains().chain_points(ci).end - 1)
        })
        .collect();
    let skirt_tip = (0..sim.cloths().cloth_count())
        .find(|&i| sim.cloths().settings(i).name == "skirt")
        .map(|ci| sim.cloths().chains(ci)[0].end - 1);
    let mut deviation: Vec<Vec<f32>> = vec![Vec::new(); tracked.len()];
    let mut panels = Vec::new();
    let mut next_moment = 0;
    let mut sim_time = 0.0f64;
    for f in 0..=frames {
        let t = f as f32 * dt;
        let start = Instant::now();
        let m = run
            .frame(
                &c,
                &mut animator,
                t,
                if f == 0 { 0.0 } else { dt },
                &mut locals,
            )
            .map_err(|e| e.to_string())?;
        move_time += start.elapsed().as_secs_f64();
        if f > 0 {
            let mv = &run.last;
            grounded += mv.grounded as usize;
            stepped += mv.stepped as usize;
            snapped += mv.snapped as usize;
            sliding += mv.sliding as usize;
            wall += mv.hits.iter().any(|h| h.normal.y.abs() < 0.3) as usize;
        }
        events += m.events;
        end = m.component.translation;
        let current = m.state;
        let state = animator.machine().state_name(current).to_string();
        if visited.last() != Some(&state) {
            visited.push(state);
        }
        let start = Instant::now();
        sim.frame(&locals, m.component, if f == 0 { 0.0 } else { dt })
            .map_err(|e| e.to_string())?;
        let pose = sim.pose();
        sim_time += start.elapsed().as_secs_f64();
        times.push(t);
        for j in 0..n {
            let mut l = pose.locals[j];
            if sk.parent(j).is_none() {
                l = m.component * l;
            }
            rot_keys[j].push(l.rotation);
            tr_keys[j].push(l.translation);
        }
        let out = sim.chain_state().output_positions();
        let targets = sim.chain_state().target_positions();
        let cloth_out = sim.cloth_state().output_positions();
        let cloth_targets = sim.cloth_state().target_positions();
        for (k, name) in tracked.iter().enumerate() {
            let d = match (*name, skirt_tip) {
                ("skirt", Some(p)) => (cloth_out[p] - cloth_targets[p]).length(),
                _ => chain_tips[k].map_or(0.0, |p| (out[p] - targets[p]).length()),
            };
            deviation[k].push(d);
        }
        if next_moment < MOMENTS.len() && t + 0.5 * dt >= MOMENTS[next_moment] {
            next_moment += 1;
            // Side view in the character's own (model) space, lifted by its world height so
            // that jumps show.
            let lift = Vec3::new(0.0, m.component.translation.y, 0.0);
            let view = |p: Vec3| p + lift;
            let mut segments = Vec::new();
            let anim = sim.animated_models();
            for j in 0..n {
                if let (Some(p), Some(_)) = (sk.parent(j), &group_of[j]) {
                    segments.push((
                        view(anim[p].translation),
                        view(anim[j].translation),
                        [200, 205, 215],
                        2.0,
                    ));
                }
            }
            for j in 0..n {
                let Some(p) = sk.parent(j) else { continue };
                let (col, w) = match &group_of[j] {
                    Some(name) => (chain_color(name), 3.0),
                    None => ([70, 70, 70], 2.5),
                };
                segments.push((
                    view(pose.models[p].translation),
                    view(pose.models[j].translation),
                    col,
                    w,
                ));
            }
            for p in 0..sim.chains().point_count() {
                let info = sim.chains().point(p);
                if let (None, Some(parent)) = (info.joint, info.parent) {
                    let col = chain_color(&sim.chains().chain_settings(info.chain).name);
                    segments.push((view(out[parent]), view(out[p]), col, 3.0));
                }
            }
            // The cloth: virtual tips and the rings across its chains.
            for ci in 0..sim.cloths().cloth_count() {
                let col = chain_color(&sim.cloths().settings(ci).name);
                for ch in sim.cloths().chains(ci) {
                    let last = ch.end - 1;
                    if sim.cloths().joint(last).is_none() && last > ch.start {
                        segments.push((view(cloth_out[last - 1]), view(cloth_out[last]), col, 3.0));
                    }
                }
                for c in sim.cloths().constraints(ci) {
                    if c.kind == ConstraintKind::StructuralHorizontal {
                        let (a, b) = (c.a as usize, c.b as usize);
                        segments.push((view(cloth_out[a]), view(cloth_out[b]), col, 1.0));
                    }
                }
            }
            let mut circles = Vec::new();
            for col in sim.chain_state().placed_colliders() {
                let centre = view(col.transform.translation);
                match col.shape {
                    Shape::Sphere { radius, .. } => circles.push((centre, radius)),
                    Shape::Capsule { radius, length } => {
                        let axis = col.transform.rotation * Vec3::Y * (0.5 * length);
                        circles.push((centre - axis, radius));
                        circles.push((centre + axis, radius));
                        let side = Vec3::new(0.0, -axis.z, axis.y).normalize_or_zero() * radius;
                        segments.push((
                            centre - axis + side,
                            centre + axis + side,
                            [150, 200, 150],
                            1.2,
                        ));
                        segments.push((
                            centre - axis - side,
                            centre + axis - side,
                            [150, 200, 150],
                            1.2,
                        ));
                    }
                    _ => {}
                }
            }
            panels.push(Panel { segments, circles });
        }
    }
    // Baked animation: rotations of every joint, translations of those that move.
    let mut tracks = Vec::new();
    for j in 0..n {
        let moves = tr_keys[j]
            .iter()
            .any(|v| !v.abs_diff_eq(sk.rest()[j].translation, 1e-6));
        tracks.push(BakedTrack {
            node: j,
            translations: moves.then(|| tr_keys[j].clone()),
            rotations: Some(rot_keys[j].clone()),
            scales: None,
        });
    }
    let source = ExportSource::from_skeleton(sk, BoneMesh::Octahedra);
    let glb = export_glb(
        &source,
        &[BakedClip {
            name: "demo".into(),
            times,
            tracks,
            merge_into: None,
        }],
    )
    .map_err(|e| e.to_string())?;
    let bands = [
        (0.0, [236, 236, 236]),
        (1.0, [226, 238, 226]),
        (3.2, [246, 228, 222]),
        (6.3, [246, 240, 214]),
        (8.4, [226, 232, 246]),
        (10.6, [236, 236, 236]),
    ];
    let series: Vec<Series> = tracked
        .iter()
        .zip(deviation)
        .map(|(name, values)| Series {
            color: chain_color(name),
            values,
        })
        .collect();
    let png = draw_strip(&panels, &bands, &series, LevelRun::DURATION)
        .png()
        .map_err(|e| e.to_string())?;
    let glb_path = a.out.join("demo.glb");
    let png_path = a.out.join("demo.png");
    write_atomic(&glb_path, &glb)?;
    write_atomic(&png_path, &png)?;
    let simulated = sim.chains().point_count() - sim.chains().chain_count()
        + sim.cloths().simulated_joints().count()
        + sim.ropes().simulated_joints().count();
    say!(
        "tassel demo: walk up stairs, run down a ramp, jump a crate, slide along a wall ({:.1} s at {} Hz)",
        LevelRun::DURATION,
        a.fps
    );
    say!("  frames: {}", frames + 1);
    say!(
        "  controller: {} colliders; grounded {grounded} of {frames} frames, climbing steps on {stepped}, snapped down on {snapped}, sliding on {sliding}, against a wall on {wall}; ends at {:.2}",
        run.level.len(),
        end
    );
    say!(
        "  time per frame (state machine, sampling, blending and controller): {:.1} us",
        move_time * 1e6 / (frames + 1) as f64
    );
    say!(
        "  chains: {}, cloths: {} ({} points), ropes: {}, springs: {}, joints simulated: {simulated} (of {n}), colliders: {}",
        sim.chains().chain_count(),
        sim.cloths().cloth_count(),
        sim.cloths().point_count(),
        sim.ropes().len(),
        sim.springs().len(),
        sim.chains().collider_count()
    );
    say!(
        "  time per frame (secondary motion incl. pose jobs): {:.1} us",
        sim_time * 1e6 / (frames + 1) as f64
    );
    say!(
        "  teleport resets: {} (chains), {} (cloths)",
        sim.chain_state().teleport_count(),
        sim.cloth_state().reset_count()
    );
    say!("  states: {} ({events} events)", visited.join(" > "));
    say!(
        "  wrote {} ({} bytes) and {} ({} bytes)",
        glb_path.display(),
        glb.len(),
        png_path.display(),
        png.len()
    );
    Ok(())
}
