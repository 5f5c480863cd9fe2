//! `tassel demo`: the embedded character through the scripted run in its level.

use crate::demo_look::level_color;
use crate::output::write_atomic;
use glam::{Quat, Vec3};
use std::path::PathBuf;
use std::time::Instant;
use tassel::builtin::level::{demo_level, moving_colliders, LevelRun};
use tassel::builtin::{self, DemoScript};
use tassel::collide::Shape;
use tassel::dynamics::cloth::ConstraintKind;
use tassel::CharacterSim;
use tassel_gltf::{builtin_body as body, group_color};
use tassel_gltf::{export_glb, BakedClip, BakedTrack, BoneMesh, ExportSource, LevelPart, Material};
use tassel_render::{draw_strip, side_outlines, Band, Chart, ChartSeries, Panel};

/// Options of `tassel demo`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder for demo.glb and demo.png.
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Frames per second.
    #[arg(long, default_value_t = 60.0)]
    fps: f32,
    /// Also put the skeleton in demo.glb as a mesh of bone spikes (one octahedron from
    /// each joint to each child), e.g. to check the rig in a viewer.
    #[arg(long)]
    bones: bool,
}

/// When the picture's panels are taken, seconds: standing, walking, on the stairs, on
/// the ramp, in the air over the crate, along the wall, in the door, riding the platform.
const MOMENTS: [f32; 8] = [0.5, 2.0, 3.75, 5.0, 7.45, 9.6, 12.2, 16.3];

pub fn run(a: Args) -> Result<(), String> {
    if !(a.fps.is_finite() && (1.0..=1000.0).contains(&a.fps)) {
        return Err(format!("--fps {} must be 1..=1000", a.fps));
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let c = builtin::character();
    let sk = &c.skeleton;
    let mut sim = CharacterSim::new(sk.clone(), &c.rig).map_err(|e| e.to_string())?;
    // A gust on the platform: an external force the run's events switch on and off.
    sim.set_external_force(&tassel::builtin::level::gust())
        .map_err(|e| e.to_string())?;
    let mut run = LevelRun::new().map_err(|e| e.to_string())?;
    let dt = 1.0 / a.fps;
    let frames = (LevelRun::DURATION * a.fps).round() as usize;
    let mut locals = sk.rest().to_vec();
    let mut animator = DemoScript.animator(&c);
    let (mut grounded, mut stepped, mut snapped, mut sliding, mut wall) = (0, 0, 0, 0, 0);
    let (mut carried, mut door_blocked) = (0, 0);
    let mut move_time = 0.0f64;
    let mut end = Vec3::ZERO;
    let mut visited: Vec<String> = Vec::new();
    let mut events = 0usize;
    let n = sk.len();
    let mut rot_keys: Vec<Vec<Quat>> = vec![Vec::with_capacity(frames + 1); n];
    let mut tr_keys: Vec<Vec<Vec3>> = vec![Vec::with_capacity(frames + 1); n];
    let movers = moving_colliders(0.0);
    let mut mover_keys: Vec<(Vec<Vec3>, Vec<Quat>)> = vec![(Vec::new(), Vec::new()); movers.len()];
    let mut times = Vec::with_capacity(frames + 1);
    // Solver membership per joint (chain, cloth or rope name), for colours and strands.
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
    // Each group's joints in order, from the joint it hangs from.
    let mut strands: Vec<(String, Vec<usize>)> = Vec::new();
    for j in 0..n {
        let Some(name) = &group_of[j] else { continue };
        match strands.iter_mut().find(|(g, _)| g == name) {
            Some((_, joints)) => joints.push(j),
            None => {
                let root = sk.parent(j).filter(|&p| group_of[p].is_none());
                strands.push((name.clone(), root.into_iter().chain([j]).collect()));
            }
        }
    }
    // Tips whose distance from their animated place is plotted: chains by name, and the
    // skirt cloth's first chain.
    let tracked = [
        ("ponytail", "PONYTAIL TIP"),
        ("tail", "TAIL TIP"),
        ("skirt", "SKIRT HEM (FRONT)"),
        ("lock_l", "LEFT LOCK TIP"),
    ];
    let chain_tips: Vec<Option<usize>> = tracked
        .iter()
        .map(|(name, _)| {
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
        if f > 0 {
            carried += run.last.platform.is_some() as usize;
            door_blocked += run.last.hits.iter().any(|h| {
                run.level
                    .collider(h.collider)
                    .is_some_and(|c| c.name == "door")
            }) as usize;
        }
        for (k, (_, position, rotation)) in moving_colliders(t).into_iter().enumerate() {
            mover_keys[k].0.push(position);
            mover_keys[k].1.push(rotation);
        }
        let current = m.state;
        let state = animator.machine().state_name(current).to_string();
        if visited.last() != Some(&state) {
            visited.push(state);
        }
        // The door and the platform moved: the secondary motion sees this frame's level.
        sim.set_level(Some(run.level.clone()));
        for (at, event) in tassel::builtin::level::GUST_EVENTS {
            if f == (at * a.fps).round() as usize {
                sim.apply_event(event).map_err(|e| e.to_string())?;
            }
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
        for (k, (name, _)) in tracked.iter().enumerate() {
            let d = match (*name, skirt_tip) {
                ("skirt", Some(p)) => (cloth_out[p] - cloth_targets[p]).length(),
                _ => chain_tips[k].map_or(0.0, |p| (out[p] - targets[p]).length()),
            };
            deviation[k].push(d);
        }
        if next_moment < MOMENTS.len() && t + 0.5 * dt >= MOMENTS[next_moment] {
            next_moment += 1;
            // Side view in world space, so that the level shows.
            let to_world = |p: Vec3| m.component.transform_point(p);
            let mut segments = Vec::new();
            let anim = sim.animated_models();
            for j in 0..n {
                if let (Some(p), Some(_)) = (sk.parent(j), &group_of[j]) {
                    segments.push((
                        to_world(anim[p].translation),
                        to_world(anim[j].translation),
                        [200, 205, 215],
                        2.0,
                    ));
                }
            }
            for j in 0..n {
                let Some(p) = sk.parent(j) else { continue };
                if sk.parent(p).is_none() {
                    // The root's link runs from the feet to the hips: not a bone.
                    continue;
                }
                let (col, w) = match &group_of[j] {
                    Some(name) => (group_color(name), 3.0),
                    None => ([70, 70, 70], 2.5),
                };
                segments.push((
                    to_world(pose.models[p].translation),
                    to_world(pose.models[j].translation),
                    col,
                    w,
                ));
            }
            for p in 0..sim.chains().point_count() {
                let info = sim.chains().point(p);
                if let (None, Some(parent)) = (info.joint, info.parent) {
                    let col = group_color(&sim.chains().chain_settings(info.chain).name);
                    segments.push((to_world(out[parent]), to_world(out[p]), col, 3.0));
                }
            }
            // The cloth: virtual tips and the rings across its chains.
            for ci in 0..sim.cloths().cloth_count() {
                let col = group_color(&sim.cloths().settings(ci).name);
                for ch in sim.cloths().chains(ci) {
                    let last = ch.end - 1;
                    if sim.cloths().joint(last).is_none() && last > ch.start {
                        segments.push((
                            to_world(cloth_out[last - 1]),
                            to_world(cloth_out[last]),
                            col,
                            3.0,
                        ));
                    }
                }
                for c in sim.cloths().constraints(ci) {
                    if c.kind == ConstraintKind::StructuralHorizontal {
                        let (a, b) = (c.a as usize, c.b as usize);
                        segments.push((to_world(cloth_out[a]), to_world(cloth_out[b]), col, 1.0));
                    }
                }
            }
            let mut circles = Vec::new();
            for col in sim.chain_state().placed_colliders() {
                let centre = to_world(col.transform.translation);
                match col.shape {
                    Shape::Sphere { radius, .. } => circles.push((centre, radius)),
                    Shape::Capsule { radius, length } => {
                        let axis = m.component.rotation
                            * (col.transform.rotation * Vec3::Y * (0.5 * length));
                        circles.push((centre - axis, radius));
                        circles.push((centre + axis, radius));
                        let side = Vec3::new(0.0, -axis.z, axis.y).normalize_or_zero() * radius;
                        for s in [side, -side] {
                            segments.push((
                                centre - axis + s,
                                centre + axis + s,
                                [150, 200, 150],
                                1.2,
                            ));
                        }
                    }
                    _ => {}
                }
            }
            // The level near the character's side plane, cut away in front of it.
            let x = m.component.translation.x;
            let mut level = Vec::new();
            for (id, c) in run.level.colliders() {
                let Some((lo, hi)) = run.level.bounds(id) else {
                    continue;
                };
                if hi.x < x - 0.6 || lo.x > x + 0.6 {
                    continue;
                }
                for outline in side_outlines(c) {
                    level.push((outline, level_color(&c.name)));
                }
            }
            panels.push(Panel {
                title: vec![format!("{t:.1} S"), m.phase.to_uppercase()],
                centre_z: m.component.translation.z,
                segments,
                circles,
                level,
            });
        }
    }
    // Baked animation: rotations of every joint, translations of those that move, and the
    // door's and the platform's poses.
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
    let mut source = ExportSource::from_skeleton(
        sk,
        if a.bones {
            BoneMesh::Octahedra
        } else {
            BoneMesh::None
        },
    );
    let colliders = demo_level();
    let mut materials: Vec<Material> = Vec::new();
    let mut parts = Vec::with_capacity(colliders.len());
    for c in &colliders {
        let kind = c.name.split(' ').next().unwrap_or("");
        let material = match materials.iter().position(|m| m.name == kind) {
            Some(i) => i,
            None => {
                materials.push(Material::srgb(kind, level_color(kind)));
                materials.len() - 1
            }
        };
        parts.push(LevelPart {
            collider: c,
            material,
        });
    }
    let level_nodes = source
        .add_level(&parts, &materials)
        .map_err(|e| e.to_string())?;
    for (k, (name, ..)) in movers.iter().enumerate() {
        let Some(i) = colliders.iter().position(|c| c.name == *name) else {
            continue;
        };
        let (translations, rotations) = std::mem::take(&mut mover_keys[k]);
        tracks.push(BakedTrack {
            node: level_nodes[i],
            translations: Some(translations),
            rotations: Some(rotations),
            scales: None,
        });
    }
    source
        .add_body(sk, &body(sk, &strands))
        .map_err(|e| e.to_string())?;
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
    let phases: Vec<(f32, &str)> = LevelRun::phases().collect();
    let shades = [
        [236, 236, 236],
        [226, 238, 226],
        [246, 228, 222],
        [246, 240, 214],
        [226, 232, 246],
    ];
    let bands = phases
        .iter()
        .enumerate()
        .map(|(k, &(start, label))| Band {
            range: (start, phases.get(k + 1).map_or(LevelRun::DURATION, |p| p.0)),
            color: shades[k % shades.len()],
            label: label.to_uppercase(),
        })
        .collect();
    let series = tracked
        .iter()
        .zip(deviation)
        .map(|((name, label), values)| ChartSeries {
            name: label.to_string(),
            color: group_color(name),
            points: values
                .into_iter()
                .enumerate()
                .map(|(f, v)| (f as f32 * dt, v))
                .collect(),
        })
        .collect();
    let chart = Chart {
        title: "HOW FAR EACH TIP IS FROM WHERE THE ANIMATION PUTS IT".into(),
        x_label: "TIME (S)".into(),
        y_label: "DISTANCE (M)".into(),
        series,
        bands,
    };
    let png = draw_strip(&panels, &chart)
        .png()
        .map_err(|e| e.to_string())?;
    let glb_path = a.out.join("demo.glb");
    let png_path = a.out.join("demo.png");
    // The built-in character's rig beside its file: what a tool outside Rust (the C ABI,
    // tassel-three's demo page) loads with demo.glb.
    let rig_path = a.out.join("demo.rig.toml");
    let rig_text = c.rig.to_toml_string().map_err(|e| e.to_string())?;
    write_atomic(&glb_path, &glb)?;
    write_atomic(&png_path, &png)?;
    write_atomic(&rig_path, rig_text.as_bytes())?;
    // The same character as a VRM 1.0 avatar (its strands as VRM spring bones, no
    // animation): what the web example and `tassel bench` run when given no file.
    let vrm_path = a.out.join("demo.vrm");
    let vrm = tassel_gltf::builtin_avatar().map_err(|e| e.to_string())?;
    write_atomic(&vrm_path, &vrm)?;
    let simulated = sim.chains().point_count() - sim.chains().chain_count()
        + sim.cloths().simulated_joints().count()
        + sim.ropes().simulated_joints().count();
    say!(
        "tassel demo: walk up stairs, run down a ramp, jump a crate, slide along a wall, go through a door, ride a turning platform ({:.1} s at {} Hz)",
        LevelRun::DURATION,
        a.fps
    );
    say!("  frames: {}", frames + 1);
    say!(
        "  controller: {} colliders; grounded {grounded} of {frames} frames, climbing steps on {stepped}, snapped down on {snapped}, sliding on {sliding}, against a wall on {wall}, carried by the platform on {carried}, touching the door on {door_blocked}; ends at {:.2}",
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
    let [(on, _), (off, _)] = tassel::builtin::level::GUST_EVENTS;
    say!("  gust: {on:.1}–{off:.1} s on the platform (an external force, switched by events)");
    say!(
        "  wrote {} ({} bytes), {} ({} bytes) and its rig, {}; the character as a VRM 1.0 avatar, {} ({} bytes)",
        glb_path.display(),
        glb.len(),
        png_path.display(),
        png.len(),
        rig_path.display(),
        vrm_path.display(),
        vrm.len()
    );
    Ok(())
}
