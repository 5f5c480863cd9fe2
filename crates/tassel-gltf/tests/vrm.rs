//! VRM spring bones from the real files in ../shared/testdata/vrm/ (CC0 vrm-conformance
//! fixtures and pixiv's MIT sphere-collider sample): parsed settings against the files'
//! JSON, rest, hang, collider invariants, bone lengths, frame-rate independence in fixed
//! mode, VRM 0.x import, and bad input.

mod common;

use common::{testdata, vrm_files};
use glam::{Quat, Vec3};
use serde_json::Value;
use std::path::Path;
use tassel::dynamics::vrm::*;
use tassel::{Pose, Transform};
use tassel_gltf::{Model, VrmVersion};

/// The document's JSON, read here independently of the importer.
fn json_of(path: &Path) -> Value {
    let bytes = std::fs::read(path).unwrap();
    if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice(&bytes[20..20 + len]).unwrap()
    } else {
        serde_json::from_slice(&bytes).unwrap()
    }
}

fn v3(v: &Value) -> Vec3 {
    let a: Vec<f32> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect();
    Vec3::new(a[0], a[1], a[2])
}

fn f(v: &Value, key: &str, default: f32) -> f32 {
    v.get(key)
        .and_then(Value::as_f64)
        .map_or(default, |x| x as f32)
}

#[test]
fn parsed_settings_match_each_files_json() {
    for path in vrm_files() {
        let name = path.display().to_string();
        let model = tassel_gltf::load(&path).unwrap();
        let vrm = model
            .vrm
            .as_ref()
            .unwrap_or_else(|| panic!("{name}: no springs"));
        assert_eq!(vrm.version, VrmVersion::V1, "{name}");
        let bones = &vrm.springs;
        let json = json_of(&path);
        let sb = &json["extensions"]["VRMC_springBone"];
        let node = |j: usize| model.joint_to_node[j] as u64;

        let colliders = sb["colliders"].as_array().cloned().unwrap_or_default();
        assert_eq!(bones.colliders.len(), colliders.len(), "{name}");
        for (c, jc) in bones.colliders.iter().zip(&colliders) {
            assert_eq!(node(c.joint), jc["node"].as_u64().unwrap(), "{name}");
            // The extended collider, when present, wins over the base shape.
            let ext = &jc["extensions"]["VRMC_springBone_extended_collider"]["shape"];
            let (shape, extended) = if ext.is_object() {
                (ext, true)
            } else {
                (&jc["shape"], false)
            };
            match c.shape {
                VrmShape::Sphere {
                    offset,
                    radius,
                    inside,
                } => {
                    let s = &shape["sphere"];
                    assert_eq!(offset, v3(&s["offset"]), "{name}");
                    assert_eq!(radius, f(s, "radius", 0.0), "{name}");
                    assert_eq!(inside, s["inside"].as_bool().unwrap_or(false), "{name}");
                    assert!(extended || !inside);
                }
                VrmShape::Capsule {
                    offset,
                    tail,
                    radius,
                    inside,
                } => {
                    let s = &shape["capsule"];
                    assert_eq!(offset, v3(&s["offset"]), "{name}");
                    assert_eq!(tail, v3(&s["tail"]), "{name}");
                    assert_eq!(radius, f(s, "radius", 0.0), "{name}");
                    assert_eq!(inside, s["inside"].as_bool().unwrap_or(false), "{name}");
                }
                VrmShape::Plane { offset, normal } => {
                    assert!(extended, "{name}: a plane needs the extension");
                    let s = &shape["plane"];
                    assert_eq!(offset, v3(&s["offset"]), "{name}");
                    assert_eq!(normal, v3(&s["normal"]), "{name}");
                }
            }
        }
        let groups = sb["colliderGroups"].as_array().cloned().unwrap_or_default();
        assert_eq!(bones.collider_groups.len(), groups.len(), "{name}");
        for (g, jg) in bones.collider_groups.iter().zip(&groups) {
            let want: Vec<usize> = jg["colliders"]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_u64().unwrap() as usize)
                .collect();
            assert_eq!(g.colliders, want, "{name}");
        }
        let springs = sb["springs"].as_array().unwrap();
        assert_eq!(bones.springs.len(), springs.len(), "{name}");
        for (s, js) in bones.springs.iter().zip(springs) {
            assert_eq!(s.name, js["name"].as_str().unwrap_or(""), "{name}");
            let joints = js["joints"].as_array().unwrap();
            // In VRM 1.0 the last joint is only the tail of the one before.
            assert_eq!(s.joints.len(), joints.len() - 1, "{name}");
            for (k, j) in s.joints.iter().enumerate() {
                let jj = &joints[k];
                assert_eq!(node(j.joint), jj["node"].as_u64().unwrap(), "{name}");
                let VrmTail::Joint(t) = j.tail else {
                    panic!("{name}: VRM 1.0 tails are joints")
                };
                assert_eq!(node(t), joints[k + 1]["node"].as_u64().unwrap(), "{name}");
                // Schema defaults for missing fields.
                assert_eq!(j.hit_radius, f(jj, "hitRadius", 0.0), "{name}");
                assert_eq!(j.stiffness, f(jj, "stiffness", 1.0), "{name}");
                assert_eq!(j.gravity_power, f(jj, "gravityPower", 0.0), "{name}");
                assert_eq!(j.drag_force, f(jj, "dragForce", 0.5), "{name}");
                let dir = jj.get("gravityDir").map_or(Vec3::NEG_Y, v3);
                assert_eq!(j.gravity_dir, dir, "{name}");
            }
            let want_groups: Vec<usize> = js["colliderGroups"]
                .as_array()
                .map(|a| a.iter().map(|x| x.as_u64().unwrap() as usize).collect())
                .unwrap_or_default();
            assert_eq!(s.collider_groups, want_groups, "{name}");
            assert_eq!(
                s.center.map(node),
                js.get("center").and_then(Value::as_u64),
                "{name}"
            );
        }
        // The extended collider files omit the extension's specVersion: accepted, warned.
        if name.contains("extended") {
            assert!(
                model.warnings.iter().any(|w| w.contains("specVersion")),
                "{name}: {:?}",
                model.warnings
            );
        }
    }
}

/// One character run on a loaded model's springs.
struct Run {
    model: Model,
    rig: VrmRig,
    state: VrmState,
    pose: Pose,
}

impl Run {
    fn new(model: Model, bones: &VrmSpringBones, options: VrmOptions) -> Self {
        let rig = VrmRig::new(&model.skeleton, bones, options).unwrap();
        let state = VrmState::new(&rig);
        let pose = Pose::rest(&model.skeleton);
        Self {
            model,
            rig,
            state,
            pose,
        }
    }

    fn frame(&mut self, component: Transform, dt: f32) {
        let sk = &self.model.skeleton;
        self.pose.locals.copy_from_slice(sk.rest());
        self.pose.update_models(sk, &Transform::IDENTITY).unwrap();
        VrmJob {
            skeleton: sk,
            rig: &self.rig,
            state: &mut self.state,
            component,
            dt,
            locals: &mut self.pose.locals,
            models: &mut self.pose.models,
        }
        .run()
        .unwrap();
    }

    /// Each link's joint and tail in world space, from the output pose.
    fn joints_and_tails(&self, component: &Transform) -> Vec<(Vec3, Vec3)> {
        self.rig
            .links
            .iter()
            .map(|l| {
                let w = *component * self.pose.models[l.joint];
                let tail = match l.tail_joint {
                    Some(t) => component.transform_point(self.pose.models[t].translation),
                    None => w.transform_point(l.tail_local),
                };
                (w.translation, tail)
            })
            .collect()
    }
}

fn loaded(path: &Path) -> (Model, VrmSpringBones) {
    let model = tassel_gltf::load(path).unwrap();
    let bones = model.vrm.clone().unwrap().springs;
    (model, bones)
}

#[test]
fn no_motion_and_no_gravity_stays_at_rest() {
    for path in vrm_files() {
        let (model, mut bones) = loaded(&path);
        for s in &mut bones.springs {
            // Colliders are dropped here: several fixtures start with the chain inside
            // one on purpose (the collision tests below cover them).
            s.collider_groups.clear();
            for j in &mut s.joints {
                j.gravity_power = 0.0;
            }
        }
        for mode in [VrmMode::Spec, VrmMode::Fixed] {
            let mut run = Run::new(
                model.clone(),
                &bones,
                VrmOptions {
                    mode,
                    ..Default::default()
                },
            );
            let rest = run.joints_and_tails(&Transform::IDENTITY);
            run.frame(Transform::IDENTITY, 0.0);
            for _ in 0..300 {
                run.frame(Transform::IDENTITY, 1.0 / 60.0);
            }
            for ((a, b), (c, d)) in rest.iter().zip(run.joints_and_tails(&Transform::IDENTITY)) {
                assert!(
                    a.distance(c) < 1e-5 && b.distance(d) < 1e-5,
                    "{}: moved from {a},{b} to {c},{d}",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn with_no_stiffness_gravity_makes_it_hang() {
    for path in vrm_files() {
        let (model, mut bones) = loaded(&path);
        for s in &mut bones.springs {
            s.collider_groups.clear();
            for j in &mut s.joints {
                j.stiffness = 0.0;
                j.gravity_power = 1.0;
                j.gravity_dir = Vec3::NEG_Y;
            }
        }
        // Lay the character on its side so that every chain starts off the vertical.
        let side = Transform::from_translation_rotation(
            Vec3::ZERO,
            Quat::from_rotation_z(std::f32::consts::FRAC_PI_2),
        );
        let mut run = Run::new(model, &bones, VrmOptions::spec());
        let start: Vec<f32> = run
            .joints_and_tails(&side)
            .iter()
            .map(|(a, b)| (*b - *a).normalize().dot(Vec3::NEG_Y))
            .collect();
        run.frame(side, 0.0);
        for _ in 0..1200 {
            run.frame(side, 1.0 / 60.0);
        }
        for (i, (a, b)) in run.joints_and_tails(&side).iter().enumerate() {
            let down = (*b - *a).normalize().dot(Vec3::NEG_Y);
            assert!(
                down > 0.9999,
                "{} link {i}: cos to down {down} (started at {})",
                path.display(),
                start[i]
            );
        }
        assert!(
            start.iter().all(|&c| c < 0.9),
            "{}: {start:?}",
            path.display()
        );
    }
}

/// Independent of the solver: how far a tail at `p` (radius `r`) is on the wrong side of
/// a collider given by the file (world transform `w` of its joint). Positive = violation.
fn violation(shape: &VrmShape, w: &Transform, p: Vec3, r: f32) -> f32 {
    match *shape {
        VrmShape::Sphere {
            offset,
            radius,
            inside,
        } => {
            let d = p.distance(w.transform_point(offset));
            if inside {
                d - (radius - r)
            } else {
                radius + r - d
            }
        }
        VrmShape::Capsule {
            offset,
            tail,
            radius,
            inside,
        } => {
            let (a, b) = (w.transform_point(offset), w.transform_point(tail));
            let t = ((p - a).dot(b - a) / (b - a).length_squared().max(1e-12)).clamp(0.0, 1.0);
            let d = p.distance(a + (b - a) * t);
            if inside {
                d - (radius - r)
            } else {
                radius + r - d
            }
        }
        VrmShape::Plane { offset, normal } => {
            let n = (w.rotation * (normal / w.scale)).normalize();
            r - (p - w.transform_point(offset)).dot(n)
        }
    }
}

/// A sway of the character: side to side, forward and back, turning, and rolling over
/// (upside down every 2 s, so that gravity throws the chains against every collider).
fn sway(t: f32) -> Transform {
    let w = std::f32::consts::TAU * t;
    let roll = std::f32::consts::FRAC_PI_2 * (1.0 - (0.5 * w).cos());
    Transform::from_translation_rotation(
        Vec3::new(
            0.15 * w.sin(),
            0.05 * (1.7 * w).sin(),
            0.1 * (0.6 * w).cos(),
        ),
        Quat::from_rotation_y(0.6 * (0.8 * w).sin()) * Quat::from_rotation_z(roll),
    )
}

/// Every file swayed for 10 s: `spec` at 60 Hz; `fixed` at 30, 60, 144 and 200 Hz, and
/// with the sway three times as fast (the colliders sweep past the tails) at 60 and
/// 144 Hz. Fixed mode's output is its last step where a step ends on the frame, else
/// that step carried on and pushed out of the frame's colliders: either way no tail may
/// end a frame inside a collider.
#[test]
fn tails_respect_colliders_and_keep_their_lengths() {
    let runs = [
        (VrmMode::Spec, 60.0, 1.0),
        (VrmMode::Fixed, 30.0, 1.0),
        (VrmMode::Fixed, 60.0, 1.0),
        (VrmMode::Fixed, 144.0, 1.0),
        (VrmMode::Fixed, 200.0, 1.0),
        (VrmMode::Fixed, 60.0, 3.0),
        (VrmMode::Fixed, 144.0, 3.0),
    ];
    for path in vrm_files() {
        let (model, bones) = loaded(&path);
        let collided = bones.springs.iter().any(|s| !s.collider_groups.is_empty());
        for (mode, hz, speed) in runs {
            let mut run = Run::new(
                model.clone(),
                &bones,
                VrmOptions {
                    mode,
                    ..Default::default()
                },
            );
            run.frame(Transform::IDENTITY, 0.0);
            let lengths: Vec<f32> = run
                .joints_and_tails(&Transform::IDENTITY)
                .iter()
                .map(|(a, b)| a.distance(*b))
                .collect();
            let (mut worst_len, mut worst_hit, mut worst_surface, mut contacts) =
                (0.0f32, f32::MIN, f32::MIN, 0);
            for f in 1..=(10.0 * hz) as u32 {
                let comp = sway(speed * f as f32 / hz);
                run.frame(comp, 1.0 / hz);
                let jt = run.joints_and_tails(&comp);
                for (i, (l, (a, b))) in run.rig.links.iter().zip(&jt).enumerate() {
                    assert!(a.is_finite() && b.is_finite());
                    worst_len = worst_len.max((a.distance(*b) - lengths[i]).abs());
                    for &c in &run.rig.link_colliders[l.colliders.clone()] {
                        let (joint, shape) = &run.rig.colliders[c];
                        let w = comp * run.pose.models[*joint];
                        let with_hit = violation(shape, &w, *b, l.hit_radius);
                        let surface = violation(shape, &w, *b, 0.0);
                        if with_hit > -1e-3 {
                            contacts += 1;
                        }
                        worst_hit = worst_hit.max(with_hit);
                        worst_surface = worst_surface.max(surface);
                    }
                }
            }
            let file = path.file_name().unwrap().to_string_lossy();
            if collided {
                println!(
                    "{file} {mode:?} {hz} Hz, sway x{speed}: length error {worst_len:.1e} m; deepest tail {:.2} mm into a collider, {:.2} mm counting hitRadius; {contacts} contacts",
                    worst_surface.max(0.0) * 1e3,
                    worst_hit.max(0.0) * 1e3,
                );
            } else {
                println!("{file} {mode:?} {hz} Hz: length error {worst_len:.1e} m; no colliders");
            }
            assert!(worst_len < 1e-5, "{}: {worst_len}", path.display());
            if collided {
                assert!(
                    contacts > 0,
                    "{}: the sway never reaches a collider",
                    path.display()
                );
                // Spec mode is the specification's single push and length projection,
                // which can leave a tail inside (the projection undoes a push along the
                // bone): its figures are printed, the equations are checked in the core
                // tests. Tassel's fixed mode settles the tail exactly: never inside a
                // collider, never outside an inside shape, never behind a plane; and it
                // keeps the hit radius clear wherever the bone can reach that far (on the
                // capsule fixture the first joint sits on the capsule's axis, 50 mm from its
                // surface with a 50 mm bone, so its tail can only touch the surface).
                if mode == VrmMode::Fixed {
                    assert!(
                        worst_surface <= 1e-5,
                        "{} fixed, {hz} Hz, sway x{speed}: tail {:.3} mm into a collider",
                        path.display(),
                        worst_surface * 1e3
                    );
                    let reachable = !path.to_string_lossy().contains("capsule");
                    assert!(
                        !reachable || worst_hit <= 1e-5,
                        "{} fixed, {hz} Hz, sway x{speed}: tail sphere {:.3} mm into a collider",
                        path.display(),
                        worst_hit * 1e3
                    );
                }
            }
        }
    }
}

/// Tip of the last link of the first spring, world space, at each frame of a sway run at
/// `hz`; and its rigid position (the rest pose carried by the character).
fn sway_run(path: &Path, mode: VrmMode, hz: f32, seconds: f32) -> (Vec<f32>, Vec<Vec3>, Vec<Vec3>) {
    let (model, bones) = loaded(path);
    let mut run = Run::new(
        model,
        &bones,
        VrmOptions {
            mode,
            ..Default::default()
        },
    );
    let last = run.rig.links.len() - 1;
    let rest_tip = run.joints_and_tails(&Transform::IDENTITY)[last].1;
    let frames = (seconds * hz).round() as usize;
    let (mut times, mut tips, mut rigid) = (vec![], vec![], vec![]);
    for f in 0..=frames {
        let t = f as f32 / hz;
        let w = std::f32::consts::TAU * t;
        let comp = Transform::from_translation_rotation(
            Vec3::new(0.3 * w.sin(), 0.0, 0.0),
            Quat::from_rotation_y(0.5 * (0.7 * w).sin()),
        );
        run.frame(comp, if f == 0 { 0.0 } else { 1.0 / hz });
        times.push(t);
        tips.push(run.joints_and_tails(&comp)[last].1);
        rigid.push(comp.transform_point(rest_tip));
    }
    (times, tips, rigid)
}

/// Fixed mode between steps is as smooth as its steps: at 144 Hz (2.4 frames a step, an
/// output step carrying the last step to each frame's time) the tip's frame-to-frame
/// second difference, RMS over 4 s of a sway at 1 and 2 Hz, is within 1.25 × the steps'
/// own (the 60 Hz run's, one step a frame, scaled by (60/144)² to 144 Hz frames): the
/// output has no jumps where steps land. (Measured 1.01–1.10×. Through `tassel simulate`
/// on `smoke_spring.vrm`, the same sways: the quadratic extrapolation of the last three
/// steps' rotations, tried first, 1.16× at 1 Hz and 2.2× at 2 Hz; the blend of the last two
/// steps that `fixed` wrote before, one step late, 1.06× and 1.13×.)
#[test]
fn fixed_mode_between_steps_is_as_smooth_as_its_steps() {
    for file in [
        "vrm/smoke_spring.vrm",
        "vrm/springbone_collider_sphere_x0p02_r0p05.vrm",
    ] {
        let Some(path) = testdata(file) else {
            return;
        };
        for freq in [1.0f32, 2.0] {
            let tips = |hz: f32| {
                let (model, bones) = loaded(&path);
                let mut run = Run::new(model, &bones, VrmOptions::default());
                let last = run.rig.links.len() - 1;
                let mut tips = vec![];
                for f in 0..=(5.0 * hz) as usize {
                    let w = std::f32::consts::TAU * freq * f as f32 / hz;
                    let comp = Transform::from_translation(Vec3::new(0.3 * w.sin(), 0.0, 0.0));
                    run.frame(comp, if f == 0 { 0.0 } else { 1.0 / hz });
                    tips.push(run.joints_and_tails(&comp)[last].1);
                }
                // After the first second: the second difference's RMS.
                let skip = hz as usize;
                let sd: Vec<f32> = (skip..tips.len() - 1)
                    .map(|i| (tips[i + 1] - 2.0 * tips[i] + tips[i - 1]).length())
                    .collect();
                (sd.iter().map(|d| d * d).sum::<f32>() / sd.len() as f32).sqrt()
            };
            let steps = tips(60.0) * (60.0f32 / 144.0).powi(2);
            let output = tips(144.0);
            println!(
                "{file} at {freq} Hz: 144 Hz output {:.3} mm, the steps' own {:.3} mm ({:.2}x)",
                output * 1e3,
                steps * 1e3,
                output / steps
            );
            assert!(
                output <= 1.25 * steps,
                "{file} at {freq} Hz: {output} against {steps}"
            );
        }
    }
}

/// RMS and largest difference of 30 and 144 Hz runs from the 60 Hz run at shared
/// instants (multiples of 1/6 s after the first second), and the RMS dynamic deviation of
/// the 60 Hz tip from its rigid position.
fn spread(path: &Path, mode: VrmMode) -> (f32, f32, f32) {
    let (t60, tip60, rigid60) = sway_run(path, mode, 60.0, 4.0);
    let (mut diff2, mut n, mut worst) = (0.0f32, 0, 0.0f32);
    for hz in [30.0, 144.0] {
        let (t, tip, _) = sway_run(path, mode, hz, 4.0);
        for (i, &ti) in t.iter().enumerate() {
            let k = (ti * 6.0).round();
            if (ti * 6.0 - k).abs() > 1e-3 || ti < 1.0 {
                continue;
            }
            let j = t60.iter().position(|&u| (u - ti).abs() < 1e-4).unwrap();
            let d = (tip[i] - tip60[j]).length();
            diff2 += d * d;
            worst = worst.max(d);
            n += 1;
        }
    }
    let dev2: f32 = tip60
        .iter()
        .zip(&rigid60)
        .skip(60)
        .map(|(a, b)| (*a - *b).length_squared())
        .sum::<f32>()
        / (tip60.len() - 60) as f32;
    ((diff2 / n as f32).sqrt(), worst, dev2.sqrt())
}

#[test]
fn fixed_mode_looks_the_same_at_30_60_and_144_hz() {
    let Some(path) = testdata("vrm/smoke_spring.vrm") else {
        return;
    };
    let (rms, worst, dev) = spread(&path, VrmMode::Fixed);
    let (spec_rms, spec_worst, spec_dev) = spread(&path, VrmMode::Spec);
    println!(
        "fixed: 30/144 Hz vs 60 Hz rms {:.3} mm = {:.2} % of the dynamic deviation {:.1} mm (largest {:.3} mm); spec: rms {:.2} mm = {:.1} % of {:.1} mm (largest {:.2} mm)",
        rms * 1e3,
        100.0 * rms / dev,
        dev * 1e3,
        worst * 1e3,
        spec_rms * 1e3,
        100.0 * spec_rms / spec_dev,
        spec_dev * 1e3,
        spec_worst * 1e3
    );
    assert!(dev > 0.005, "the sway barely moves the spring: {dev}");
    assert!(rms < 0.01 * dev, "fixed mode: {rms} vs deviation {dev}");
    // And the spec mode does depend on the frame rate (so the comparison can fail).
    assert!(
        spec_rms > 0.02 * spec_dev,
        "spec mode: {spec_rms} vs {spec_dev}"
    );
}

/// The sphere-collider sample's JSON with its spring bones replaced by `edit`.
fn edited(edit: impl FnOnce(&mut Value)) -> Result<Model, String> {
    let path = testdata("vrm/sphere-collider.gltf").unwrap();
    let mut json = json_of(&path);
    edit(&mut json);
    let bytes = serde_json::to_vec(&json).unwrap();
    tassel_gltf::load_slice(&bytes, path.parent(), "edited.gltf").map_err(|e| e.to_string())
}

#[test]
fn vrm0_secondary_animation() {
    if testdata("vrm").is_none() {
        return;
    }
    // VRM 0.x: bone group roots whose whole subtree swings, virtual 7 cm tails at leaves,
    // collider offsets with z negated, UniVRM's defaults for missing fields.
    let model = edited(|j| {
        let ext = j["extensions"].as_object_mut().unwrap();
        ext.remove("VRMC_springBone");
        ext.insert(
            "VRM".into(),
            serde_json::json!({
                "secondaryAnimation": {
                    "colliderGroups": [{
                        "node": 5,
                        "colliders": [{"offset": {"x": 0.1, "y": 0.2, "z": 0.3}, "radius": 0.5}]
                    }],
                    "boneGroups": [{
                        "comment": "tail",
                        "stiffiness": 0.8,
                        "gravityPower": 0.3,
                        "gravityDir": {"x": 0, "y": -1, "z": 0},
                        "center": -1,
                        "bones": [1],
                        "colliderGroups": [0]
                    }]
                }
            }),
        );
        j["extensionsUsed"] = serde_json::json!(["VRM"]);
    })
    .unwrap();
    let vrm = model.vrm.as_ref().unwrap();
    assert_eq!(vrm.version, VrmVersion::V0);
    let b = &vrm.springs;
    let node = |j: usize| model.joint_to_node[j];
    assert_eq!(b.colliders.len(), 1);
    assert_eq!(node(b.colliders[0].joint), 5);
    assert_eq!(
        b.colliders[0].shape,
        VrmShape::Sphere {
            offset: Vec3::new(0.1, 0.2, -0.3),
            radius: 0.5,
            inside: false
        }
    );
    let s = &b.springs[0];
    assert_eq!(s.name, "tail");
    assert_eq!(s.center, None);
    assert_eq!(s.collider_groups, vec![0]);
    // Root node 1 (Spring B) and its descendants C, D, E (nodes 2, 3, 4) swing.
    let nodes: Vec<usize> = s.joints.iter().map(|j| node(j.joint)).collect();
    assert_eq!(nodes, vec![1, 2, 3, 4]);
    for (k, j) in s.joints.iter().enumerate() {
        assert_eq!(j.stiffness, 0.8);
        assert_eq!(j.gravity_power, 0.3);
        assert_eq!(j.drag_force, 0.4, "UniVRM's default");
        assert_eq!(j.hit_radius, 0.02, "UniVRM's default");
        match j.tail {
            VrmTail::Joint(t) => assert_eq!(node(t), nodes[k] + 1),
            // Spring E's local translation is (0, -2, 0): 7 cm along it.
            VrmTail::Local(p) => {
                assert_eq!(k, 3);
                assert!(p.abs_diff_eq(Vec3::new(0.0, -0.07, 0.0), 1e-7), "{p}");
            }
        }
    }
    // It runs: lengths kept, no NaN.
    let bones = b.clone();
    let mut run = Run::new(model, &bones, VrmOptions::spec());
    run.frame(Transform::IDENTITY, 0.0);
    let l0: Vec<f32> = run
        .joints_and_tails(&Transform::IDENTITY)
        .iter()
        .map(|(a, b)| a.distance(*b))
        .collect();
    // The virtual tail: 7 cm in Spring E's space, which the root scales by 0.25.
    assert!((l0[3] - 0.0175).abs() < 1e-6, "{}", l0[3]);
    for f in 1..=300 {
        let comp = sway(f as f32 / 60.0);
        run.frame(comp, 1.0 / 60.0);
        for (k, (a, b)) in run.joints_and_tails(&comp).iter().enumerate() {
            assert!(((a.distance(*b)) - l0[k]).abs() < 1e-5);
        }
    }
}

#[test]
fn bad_spring_bones_are_clear_errors() {
    if testdata("vrm").is_none() {
        return;
    }
    fn springs(j: &mut Value) -> &mut Value {
        &mut j["extensions"]["VRMC_springBone"]["springs"]
    }
    type Edit = Box<dyn FnOnce(&mut Value)>;
    let cases: Vec<(Edit, &str)> = vec![
        (
            Box::new(|j| springs(j)[0]["joints"][1]["node"] = 99.into()),
            "springs[0].joints[1].node names node 99, which does not exist",
        ),
        (
            Box::new(|j| {
                let s = springs(j)[0].clone();
                springs(j).as_array_mut().unwrap().push(s);
            }),
            "already in VRM spring 0",
        ),
        (
            Box::new(|j| springs(j)[0]["joints"][0]["hitRadius"] = (-0.5).into()),
            "hitRadius -0.5 must be ≥ 0",
        ),
        (
            Box::new(|j| {
                springs(j)[0]["joints"][0]["gravityDir"] = serde_json::json!(["NaN", -1, 0])
            }),
            "gravityDir must be 3 finite numbers",
        ),
        (
            Box::new(|j| springs(j)[0]["colliderGroups"] = serde_json::json!([4])),
            "collider group 4, which does not exist",
        ),
        (
            Box::new(|j| {
                j["extensions"]["VRMC_springBone"]["colliders"][0]["shape"] =
                    serde_json::json!({"plane": {"normal": [0, 1, 0]}})
            }),
            "planes belong to VRMC_springBone_extended_collider",
        ),
        (
            Box::new(|j| {
                // A tail that is not below its head.
                springs(j)[0]["joints"][1]["node"] = 5.into();
            }),
            "is not below the joint",
        ),
    ];
    for (edit, want) in cases {
        let e = edited(edit).expect_err(want);
        assert!(e.contains(want), "'{e}' does not say '{want}'");
        assert!(e.contains("edited.gltf"), "{e}");
    }
}

/// Every tail of `path` (world space) at the instants k/6 s of a 6 s run at `hz`: the
/// character swayed ±0.3 m at 1 Hz and turned ±0.5 rad at 0.7 Hz; and the tails carried
/// rigidly with the character.
fn all_tails(path: &Path, hz: u32) -> (Vec<Vec<Vec3>>, Vec<Vec<Vec3>>) {
    let (model, bones) = loaded(path);
    let mut run = Run::new(
        model,
        &bones,
        VrmOptions {
            mode: VrmMode::Fixed,
            ..Default::default()
        },
    );
    let rest: Vec<Vec3> = run
        .joints_and_tails(&Transform::IDENTITY)
        .iter()
        .map(|jt| jt.1)
        .collect();
    let (mut tails, mut rigid) = (vec![], vec![]);
    for f in 0..=6 * hz {
        let t = f as f64 / hz as f64;
        let w = std::f64::consts::TAU * t;
        let comp = Transform::from_translation_rotation(
            Vec3::new((0.3 * w.sin()) as f32, 0.0, 0.0),
            Quat::from_rotation_y((0.5 * (0.7 * w).sin()) as f32),
        );
        run.frame(comp, if f == 0 { 0.0 } else { 1.0 / hz as f32 });
        if (f * 6) % hz == 0 {
            tails.push(run.joints_and_tails(&comp).iter().map(|jt| jt.1).collect());
            rigid.push(rest.iter().map(|&p| comp.transform_point(p)).collect());
        }
    }
    (tails, rigid)
}

/// Issue 15's target for VRM fixed mode: on every VRM file of the test data, 30 and 60 Hz
/// against 144 Hz within 1 % (RMS difference of every tail at the shared instants,
/// relative to the tails' RMS dynamic deviation at 144 Hz).
#[test]
fn fixed_mode_on_every_file_within_1_percent_across_frame_rates() {
    let files = vrm_files();
    if files.is_empty() {
        return;
    }
    let mut failures = vec![];
    for path in files {
        let (reference, rigid) = all_tails(&path, 144);
        let (mut dev2, mut n) = (0.0f64, 0usize);
        for (s, r) in reference.iter().zip(&rigid) {
            for (a, b) in s.iter().zip(r) {
                dev2 += (*a - *b).length_squared() as f64;
                n += 1;
            }
        }
        let dev = (dev2 / n as f64).sqrt();
        for hz in [30, 60] {
            let (other, _) = all_tails(&path, hz);
            let mut d2 = 0.0f64;
            for (s, r) in other.iter().zip(&reference) {
                for (a, b) in s.iter().zip(r) {
                    d2 += (*a - *b).length_squared() as f64;
                }
            }
            let rel = (d2 / n as f64).sqrt() / dev;
            let name = path.file_name().unwrap().to_string_lossy();
            println!(
                "{name}: fixed {hz} Hz vs 144 Hz: {:.3} % of the tails' RMS dynamic deviation ({:.1} mm)",
                100.0 * rel,
                dev * 1e3
            );
            // A knife-edge, excluded by name: this fixture's first joint sits on the
            // capsule's axis with a bone exactly as long as the capsule's radius, so
            // every place its tail may take lies on one circle around the axis and
            // rounding picks the point (measured: about 30 % at 30 and 60 Hz).
            let knife_edge = name == "springbone_collider_capsule_x0p02_r0p05.vrm";
            if rel > 0.01 && !knife_edge {
                failures.push(format!("{name} at {hz} Hz: {:.2} %", 100.0 * rel));
            }
        }
    }
    assert!(failures.is_empty(), "over 1 %: {}", failures.join(", "));
}

/// VRMC_node_constraint: read from the nodes (the first of roll, aim, rotation), with
/// UniVRM's defaults (weight 1, roll about X, aim along +X); bad entries are errors that
/// name them; an unknown specVersion is skipped with a warning.
#[test]
fn node_constraints_are_read_and_bad_ones_named() {
    use tassel::dynamics::vrm::ConstraintKind;
    if testdata("vrm").is_none() {
        return;
    }
    let with = |ext: Value| {
        edited(|j| {
            j["extensionsUsed"] = serde_json::json!(["VRMC_springBone", "VRMC_node_constraint"]);
            j["nodes"][5]["extensions"] = serde_json::json!({ "VRMC_node_constraint": ext });
        })
    };
    let ok = with(serde_json::json!({"specVersion": "1.0", "constraint": {"roll": {"source": 1}}}))
        .unwrap();
    let c = ok.vrm.as_ref().unwrap().springs.node_constraints[0];
    assert_eq!(ok.joint_to_node[c.destination], 5);
    assert_eq!(ok.joint_to_node[c.source], 1);
    assert_eq!(c.kind, ConstraintKind::Roll { axis: Vec3::X });
    assert_eq!(c.weight, 1.0);
    let aim = with(serde_json::json!({"specVersion": "1.0", "constraint": {"aim": {"source": 2, "aimAxis": "NegativeZ", "weight": 0.25}}}))
        .unwrap();
    let c = aim.vrm.as_ref().unwrap().springs.node_constraints[0];
    assert_eq!(c.kind, ConstraintKind::Aim { axis: Vec3::NEG_Z });
    assert_eq!(c.weight, 0.25);
    for (ext, says) in [
        (
            serde_json::json!({"specVersion": "1.0", "constraint": {"roll": {"source": 99}}}),
            "node 99",
        ),
        (
            serde_json::json!({"specVersion": "1.0", "constraint": {"roll": {"source": 1, "rollAxis": "W"}}}),
            "rollAxis",
        ),
        (
            serde_json::json!({"specVersion": "1.0", "constraint": {"aim": {"source": 1, "aimAxis": "Up"}}}),
            "axis",
        ),
        (
            serde_json::json!({"specVersion": "1.0", "constraint": {"rotation": {"source": 1, "weight": 1.5}}}),
            "weight",
        ),
        (
            serde_json::json!({"specVersion": "1.0", "constraint": {"rotation": {"source": 5}}}),
            "itself",
        ),
    ] {
        let e = with(ext).expect_err(says);
        assert!(e.contains(says) && e.contains("nodes[5]"), "{e}");
    }
    let skipped =
        with(serde_json::json!({"specVersion": "2.0", "constraint": {"roll": {"source": 1}}}))
            .unwrap();
    assert!(skipped
        .vrm
        .as_ref()
        .unwrap()
        .springs
        .node_constraints
        .is_empty());
    assert!(skipped.warnings.iter().any(|w| w.contains("specVersion")));
}

#[test]
fn reset_is_a_fresh_start_on_every_file() {
    // After reset() the springs run exactly as a new character's on the same input, in
    // every mode: nothing of the earlier motion leaks through.
    for path in vrm_files() {
        let model = tassel_gltf::load(&path).unwrap();
        let springs = model.vrm.as_ref().unwrap().springs.clone();
        for mode in [VrmMode::Spec, VrmMode::ThreeVrm, VrmMode::Fixed] {
            let options = VrmOptions {
                mode,
                ..VrmOptions::default()
            };
            let mut used = tassel::CharacterSim::with_vrm(
                model.skeleton.clone(),
                &Default::default(),
                &springs,
                options,
            )
            .unwrap();
            let mut fresh = used.clone();
            let rest = model.skeleton.rest().to_vec();
            let at = |t: f32| {
                Transform::from_translation_rotation(
                    Vec3::new(0.3 * (5.0 * t).sin(), 0.0, 0.0),
                    Quat::from_rotation_y(0.5 * (3.0 * t).sin()),
                )
            };
            for k in 0..23 {
                let dt = if k == 0 { 0.0 } else { 1.0 / 60.0 };
                used.frame(&rest, at(k as f32 / 60.0), dt).unwrap();
            }
            used.reset();
            for k in 0..60 {
                let t = 1.0 + k as f32 / 60.0;
                let dt = if k == 0 { 0.0 } else { 1.0 / 60.0 };
                let a = used.frame(&rest, at(t), dt).unwrap().clone();
                let b = fresh.frame(&rest, at(t), dt).unwrap();
                assert_eq!(
                    a.locals,
                    b.locals,
                    "{} {mode:?}: frame {k} after the reset",
                    path.display()
                );
            }
        }
    }
}

/// `VRMC_springBone_limit` (draft 1.0): each joint's limit read as the file gives it (angles
/// in radians, the rotation as x y z w), the last joint's (a tail only) ignored with a
/// warning, bad limits named by their path in the file.
#[test]
fn spring_bone_limits_are_read_and_bad_ones_named() {
    use tassel::dynamics::vrm::{VrmLimit, VrmLimitShape};
    if testdata("vrm").is_none() {
        return;
    }
    fn joints(j: &mut Value) -> &mut Value {
        &mut j["extensions"]["VRMC_springBone"]["springs"][0]["joints"]
    }
    let with = |limits: Vec<(usize, Value)>| {
        edited(move |j| {
            j["extensionsUsed"] = serde_json::json!(["VRMC_springBone", "VRMC_springBone_limit"]);
            for (k, limit) in limits {
                joints(j)[k]["extensions"] = serde_json::json!({
                    "VRMC_springBone_limit": {"specVersion": "1.0-draft", "limit": limit}
                });
            }
        })
    };
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let model = with(vec![
        (
            0,
            serde_json::json!({"cone": {"angle": 0.5, "rotation": [h, 0.0, 0.0, h]}}),
        ),
        (1, serde_json::json!({"hinge": {"angle": 1.25}})),
        (
            2,
            serde_json::json!({"spherical": {"pitch": 0.75, "yaw": 0.25}}),
        ),
        (4, serde_json::json!({"cone": {"angle": 0.1}})),
    ])
    .unwrap();
    let springs = &model.vrm.as_ref().unwrap().springs.springs[0];
    // Joints 0..=3 turn (4 is the last tail).
    let limit = |k: usize| springs.joints[k].limit;
    assert_eq!(
        limit(0),
        Some(VrmLimit {
            shape: VrmLimitShape::Cone { angle: 0.5 },
            rotation: glam::Quat::from_xyzw(h, 0.0, 0.0, h),
        })
    );
    assert_eq!(
        limit(1),
        Some(VrmLimit::new(VrmLimitShape::Hinge { angle: 1.25 }))
    );
    assert_eq!(
        limit(2),
        Some(VrmLimit::new(VrmLimitShape::Spherical {
            pitch: 0.75,
            yaw: 0.25
        }))
    );
    assert_eq!(limit(3), None);
    assert!(
        model
            .warnings
            .iter()
            .any(|w| w.contains("joints[4]") && w.contains("limit is ignored")),
        "{:?}",
        model.warnings
    );
    // Compiled for the skeleton: three limited links.
    let rig = tassel::dynamics::vrm::VrmRig::new(
        &model.skeleton,
        &model.vrm.as_ref().unwrap().springs,
        Default::default(),
    )
    .unwrap();
    assert_eq!(rig.links.iter().filter(|l| l.limit.is_some()).count(), 3);
    for (limit, says) in [
        (
            serde_json::json!({"cone": {"angle": -0.2}}),
            "joints[1].extensions.VRMC_springBone_limit.limit.cone.angle is -0.2",
        ),
        (
            serde_json::json!({"spherical": {"pitch": 0.2}}),
            "limit.spherical.yaw is missing",
        ),
        (
            serde_json::json!({"cone": {"angle": 0.2}, "hinge": {"angle": 0.2}}),
            "has 2 (cone, hinge); the draft allows exactly one",
        ),
        (serde_json::json!({}), "has none of cone, hinge, spherical"),
        (
            serde_json::json!({"hinge": {"angle": 0.2, "rotation": [0, 0, 1]}}),
            "limit.hinge.rotation must be 4 numbers",
        ),
    ] {
        let e = with(vec![(1, limit)]).expect_err(says);
        assert!(e.contains(says), "'{e}' does not say '{says}'");
        assert!(e.contains("edited.gltf"), "{e}");
    }
}
