//! What `tassel demo` writes, read back independently: demo.glb holds every collider of
//! the demo level where the level puts it, the door's and the platform's motion, and a
//! body skinned to the skeleton (smooth at the joints, nothing on the root); demo.png has
//! titled panels showing the level and a chart with axes and a legend.

mod common;

use common::{glb_chunks, read_floats, read_png, read_u16s, run_ok, tassel, tmp, validate};
use glam::{Quat, Vec3};
use serde_json::Value;
use std::path::Path;
use tassel::builtin::level::{demo_level, moving_colliders};
use tassel::controller::Level;

fn run_demo(dir: &Path, extra: &[&str]) {
    run_ok(tassel().args(["demo", "--out"]).arg(dir).args(extra));
}

/// Accessor `i` as f64 components (FLOAT or UNSIGNED_SHORT), read by hand.
fn read(doc: &Value, bin: &[u8], i: usize) -> Vec<f64> {
    match doc["accessors"][i]["componentType"].as_u64().unwrap() {
        5123 => read_u16s(doc, bin, i).into_iter().map(f64::from).collect(),
        _ => read_floats(doc, bin, i)
            .into_iter()
            .map(f64::from)
            .collect(),
    }
}

fn node_named<'a>(doc: &'a Value, name: &str) -> Option<(usize, &'a Value)> {
    doc["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .find(|(_, n)| n["name"] == name)
}

#[test]
fn demo_glb_has_the_level_where_it_is_its_motion_and_a_skinned_body() {
    let dir = tmp("demo-glb");
    run_demo(&dir, &[]);
    let path = dir.join("demo.glb");
    if let Some(report) = validate(&path) {
        assert!(report.contains("\"errors\":0"), "{report}");
    }
    let glb = std::fs::read(&path).unwrap();
    println!("demo.glb: {} bytes", glb.len());
    let (doc, bin) = glb_chunks(&glb);

    // Every collider of the level is a mesh node whose vertices (the node's transform
    // applied, read back by the glTF importer) span the collider's bounds as the
    // controller's level computes them from its own primitives.
    let colliders = demo_level();
    let level = Level::new(colliders.clone()).unwrap();
    let model = tassel_gltf::load(&path).unwrap();
    for (id, c) in level.colliders() {
        let (node, _) = node_named(&doc, &c.name).unwrap_or_else(|| panic!("no node {}", c.name));
        let inst = model
            .meshes
            .iter()
            .find(|m| m.node == node)
            .unwrap_or_else(|| panic!("node {} has no mesh", c.name));
        let (lo, hi) = inst.vertices.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        let (blo, bhi) = level.bounds(id).unwrap();
        assert!(
            lo.abs_diff_eq(blo, 2e-3) && hi.abs_diff_eq(bhi, 2e-3),
            "{}: mesh spans {lo}..{hi}, the collider {blo}..{bhi}",
            c.name
        );
    }
    assert_eq!(level.len(), colliders.len());

    // The door and the platform are keyed: at 12.2 s the door is up (open), at the end
    // the platform has moved and turned a quarter turn, as the level's script says.
    let anim = &doc["animations"][0];
    let times = read(
        &doc,
        &bin,
        anim["samplers"][0]["input"].as_u64().unwrap() as usize,
    );
    let key = |node: usize, path: &str, t: f64| -> Vec<f64> {
        let ch = anim["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["node"] == node && c["target"]["path"] == path)
            .unwrap_or_else(|| panic!("node {node} has no {path} channel"));
        let s = &anim["samplers"][ch["sampler"].as_u64().unwrap() as usize];
        let out = read(&doc, &bin, s["output"].as_u64().unwrap() as usize);
        let k = times.iter().position(|&x| (x - t).abs() < 1e-4).unwrap();
        let w = if path == "rotation" { 4 } else { 3 };
        out[k * w..k * w + w].to_vec()
    };
    let (door, _) = node_named(&doc, "door").unwrap();
    let (platform, _) = node_named(&doc, "platform").unwrap();
    let at_12_2 = key(door, "translation", 12.2);
    assert!(
        at_12_2[1] > 2.3,
        "the door is not open at 12.2 s: {at_12_2:?}"
    );
    let last = *times.last().unwrap();
    let (_, p_end, r_end) = moving_colliders(last as f32)[1];
    let p = key(platform, "translation", last);
    assert!((Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) - p_end).length() < 1e-5);
    let r = key(platform, "rotation", last);
    let r = Quat::from_xyzw(r[0] as f32, r[1] as f32, r[2] as f32, r[3] as f32);
    assert!(r.angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)) < 1e-3);
    assert!(r_end.angle_between(Quat::IDENTITY) > 1.5);

    // The body: one skinned mesh; no vertex on the root (the feet-to-hips link is no
    // bone); weights sum to 1; some vertices at each knee shared half and half between
    // thigh and shin; every simulated group has geometry on its joints.
    let (_, body) = node_named(&doc, "body").expect("a body node");
    assert!(body["skin"].is_u64());
    assert!(
        node_named(&doc, "bones").is_none(),
        "bone spikes without --bones"
    );
    let joint_names: Vec<String> = doc["nodes"].as_array().unwrap()[..model.skeleton.len()]
        .iter()
        .map(|n| n["name"].as_str().unwrap_or("").to_string())
        .collect();
    let find = |n: &str| joint_names.iter().position(|x| x == n).unwrap();
    let mesh = &doc["meshes"][body["mesh"].as_u64().unwrap() as usize];
    let (mut used, mut knees) = (vec![false; joint_names.len()], 0);
    for prim in mesh["primitives"].as_array().unwrap() {
        let j = read(
            &doc,
            &bin,
            prim["attributes"]["JOINTS_0"].as_u64().unwrap() as usize,
        );
        let w = read(
            &doc,
            &bin,
            prim["attributes"]["WEIGHTS_0"].as_u64().unwrap() as usize,
        );
        for (jv, wv) in j.chunks(4).zip(w.chunks(4)) {
            assert!((wv.iter().sum::<f64>() - 1.0).abs() < 1e-6, "{wv:?}");
            for (&jj, &ww) in jv.iter().zip(wv) {
                if ww > 0.0 {
                    used[jj as usize] = true;
                }
            }
            let has = |n: &str, x: f64| {
                jv.iter()
                    .zip(wv)
                    .any(|(&jj, &ww)| jj as usize == find(n) && (ww - x).abs() < 1e-6)
            };
            knees += (has("thigh_l", 0.5) && has("shin_l", 0.5)) as usize;
        }
    }
    assert!(!used[find("root")], "a vertex is skinned to the root");
    assert!(
        knees >= 12,
        "{knees} knee vertices shared by thigh and shin"
    );
    for n in [
        "hips",
        "head",
        "hand_r",
        "ponytail_4",
        "lock_l_2",
        "tail_6",
        "skirt_3_2",
        "charm_4",
    ] {
        assert!(used[find(n)], "nothing skinned to {n}");
    }

    // --bones adds the spikes (and the file still validates).
    let dir = tmp("demo-bones");
    run_demo(&dir, &["--bones"]);
    let (doc, _) = glb_chunks(&std::fs::read(dir.join("demo.glb")).unwrap());
    assert!(node_named(&doc, "bones").is_some());
    if let Some(report) = validate(&dir.join("demo.glb")) {
        assert!(report.contains("\"errors\":0"), "{report}");
    }
}

#[test]
fn demo_png_has_titles_the_level_and_a_chart_with_axes_and_a_legend() {
    use tassel_render::{CHART_HEIGHT, PANEL_WIDTH, TITLE_HEIGHT};
    let dir = tmp("demo-png");
    run_demo(&dir, &[]);
    let (w, h, px) = read_png(&dir.join("demo.png"));
    let at = |x: usize, y: usize| {
        [
            px[(y * w + x) * 3],
            px[(y * w + x) * 3 + 1],
            px[(y * w + x) * 3 + 2],
        ]
    };
    let count = |x0: usize, x1: usize, y0: usize, y1: usize, f: &dyn Fn([u8; 3]) -> bool| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| f(at(x, y)))
            .count()
    };
    let panels = 8;
    assert_eq!(w, panels * PANEL_WIDTH);
    let panel_h = h - CHART_HEIGHT;
    let title_ink = |c: [u8; 3]| c == [40, 40, 40];
    let floor = |c: [u8; 3]| c == [196, 198, 192];
    let bone = |c: [u8; 3]| c == [70, 70, 70];
    let ponytail = |c: [u8; 3]| c == [235, 120, 20];
    for i in 0..panels {
        let x0 = i * PANEL_WIDTH;
        // Two title lines of 2× text: ink in each line's band, none in the view.
        assert!(
            count(x0 + 8, x0 + PANEL_WIDTH - 4, 6, 20, &title_ink) > 40,
            "panel {i}: no time"
        );
        assert!(
            count(x0 + 8, x0 + PANEL_WIDTH - 4, 25, 39, &title_ink) > 40,
            "panel {i}: no phase"
        );
        // The level: the floor's colour in the view's lower part.
        assert!(
            count(x0 + 2, x0 + PANEL_WIDTH - 2, panel_h - 40, panel_h, &floor) > 500,
            "panel {i}: no floor"
        );
        // The character in the view, and a clear margin around it: no bone or hair
        // colour in the view's top 8 rows nor in its 3 outer columns on each side.
        let view = TITLE_HEIGHT..panel_h;
        assert!(
            count(x0, x0 + PANEL_WIDTH, view.start, view.end, &bone) > 50,
            "panel {i}: no body"
        );
        assert!(
            count(x0, x0 + PANEL_WIDTH, view.start, view.end, &ponytail) > 10,
            "panel {i}: no ponytail"
        );
        let margin = |c: [u8; 3]| bone(c) || ponytail(c);
        assert_eq!(
            count(x0, x0 + PANEL_WIDTH, view.start, view.start + 8, &margin),
            0,
            "panel {i}: cut at the top"
        );
        assert_eq!(
            count(x0 + 1, x0 + 4, view.start, view.end, &margin),
            0,
            "panel {i}: cut on the left"
        );
        assert_eq!(
            count(
                x0 + PANEL_WIDTH - 3,
                x0 + PANEL_WIDTH,
                view.start,
                view.end,
                &margin
            ),
            0,
            "panel {i}: cut on the right"
        );
    }
    // The chart (tassel-render's Chart layout: plot from x = 78 to w - 20, from 40 to
    // CHART_HEIGHT - 52 below its top): a vertical axis line, a horizontal one, tick
    // labels under it, the axis titles, and the legend's four colour swatches.
    let axis = |c: [u8; 3]| c == [60, 60, 60];
    let (top, bottom) = (panel_h + 40, panel_h + CHART_HEIGHT - 52);
    assert!(
        count(78, 79, top, bottom, &axis) >= bottom - top - 1,
        "no y axis"
    );
    // The x axis (partly under the curves that sit at zero) and its tick marks below it.
    assert!(
        count(78, w - 20, bottom, bottom + 1, &axis) >= (w - 100) / 3,
        "no x axis"
    );
    assert!(
        count(78, w - 20, bottom + 2, bottom + 5, &axis) >= 4 * 3,
        "no x ticks"
    );
    assert!(
        count(60, w - 20, bottom + 9, bottom + 16, &axis) > 60,
        "no x tick labels"
    );
    assert!(
        count(w / 2 - 40, w / 2 + 40, h - 16, h - 9, &axis) > 20,
        "no x axis title"
    );
    assert!(count(10, 17, top, bottom, &axis) > 40, "no y axis title");
    let legend = (w - 300, w - 20, top, top + 80);
    for col in [[235, 120, 20], [40, 90, 220], [200, 40, 160], [210, 170, 0]] {
        let swatch = move |c: [u8; 3]| c == col;
        assert!(
            count(legend.0, legend.1, legend.2, legend.3, &swatch) >= 40,
            "no legend swatch {col:?}"
        );
    }
}
