//! `tassel inspect`: what a file holds — the node tree, skins, clips, VRM spring bones and
//! the loader's warnings. Printing only; the reading is in `tassel-gltf`.

use std::fmt::Write as _;
use std::path::PathBuf;
use tassel::anim::Interpolation;
use tassel::dynamics::vrm::{VrmShape, VrmTail};
use tassel_gltf::{Model, VrmVersion};

/// Options of `tassel inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// The file (.glb, .gltf, .vrm).
    file: PathBuf,
}

pub fn run(a: Args) -> Result<(), String> {
    let model = tassel_gltf::load(&a.file).map_err(|e| e.to_string())?;
    say!("{}", report(&a.file.display().to_string(), &model));
    Ok(())
}

fn v(p: glam::Vec3) -> String {
    format!("({:.3}, {:.3}, {:.3})", p.x, p.y, p.z)
}

/// The whole report as text.
pub fn report(name: &str, m: &Model) -> String {
    let sk = &m.skeleton;
    let mut o = String::new();
    let n = sk.len();
    let _ = writeln!(
        o,
        "{name}: {n} nodes, {} skin(s), {} clip(s)",
        m.skins.len(),
        m.clips.len()
    );
    // Nodes below each node (descendant counts), from the depth-first order.
    let mut below = vec![0usize; n];
    for j in (0..n).rev() {
        if let Some(p) = sk.parent(j) {
            below[p] += below[j] + 1;
        }
    }
    let mut depth = vec![0usize; n];
    let simulated: Vec<usize> = m
        .vrm
        .as_ref()
        .map(|v| v.springs.simulated_joints().collect())
        .unwrap_or_default();
    let _ = writeln!(
        o,
        "\nNode tree (node index, nodes below; * swings as a VRM spring):"
    );
    for j in 0..n {
        if let Some(p) = sk.parent(j) {
            depth[j] = depth[p] + 1;
        }
        let _ = writeln!(
            o,
            "  {}{}{} [node {}{}]",
            "  ".repeat(depth[j]),
            sk.name(j),
            if simulated.contains(&j) { " *" } else { "" },
            m.joint_to_node[j],
            if below[j] > 0 {
                format!(", {} below", below[j])
            } else {
                String::new()
            }
        );
    }
    for s in &m.skins {
        let _ = writeln!(o, "\nSkin '{}': {} joints", s.name, s.joints.len());
    }
    if !m.clips.is_empty() {
        let _ = writeln!(o, "\nClips:");
    }
    for c in &m.clips {
        let mut channels = 0;
        let mut kinds: Vec<&str> = Vec::new();
        for t in &c.tracks {
            let ints = [
                t.translation.as_ref().map(|c| c.interpolation),
                t.rotation.as_ref().map(|c| c.interpolation),
                t.scale.as_ref().map(|c| c.interpolation),
            ];
            for i in ints.into_iter().flatten() {
                channels += 1;
                let k = match i {
                    Interpolation::Step => "STEP",
                    Interpolation::Linear => "LINEAR",
                    Interpolation::CubicSpline => "CUBICSPLINE",
                };
                if !kinds.contains(&k) {
                    kinds.push(k);
                }
            }
        }
        let _ = writeln!(
            o,
            "  '{}': {:.3} s, {channels} channels on {} nodes, {}",
            c.name,
            c.duration,
            c.tracks.len(),
            kinds.join(" + ")
        );
    }
    if let Some(vrm) = &m.vrm {
        let b = &vrm.springs;
        let joints: usize = b.springs.iter().map(|s| s.joints.len()).sum();
        let _ = writeln!(
            o,
            "\nVRM spring bones ({}): {} spring(s), {joints} swinging joint(s), {} collider(s) in {} group(s)",
            match vrm.version {
                VrmVersion::V1 => "VRMC_springBone 1.0",
                VrmVersion::V0 => "VRM 0.x secondaryAnimation",
            },
            b.springs.len(),
            b.colliders.len(),
            b.collider_groups.len()
        );
        let node = |j: usize| format!("'{}' (node {})", sk.name(j), m.joint_to_node[j]);
        for (i, s) in b.springs.iter().enumerate() {
            let _ = writeln!(
                o,
                "  spring {i} '{}': {} joint(s), collider groups {:?}, center {}",
                s.name,
                s.joints.len(),
                s.collider_groups,
                s.center.map_or("none (world)".into(), node)
            );
            for j in &s.joints {
                let tail = match j.tail {
                    VrmTail::Joint(t) => node(t),
                    VrmTail::Local(p) => format!("virtual {} local", v(p)),
                };
                let _ = writeln!(
                    o,
                    "    {} → {tail}: hitRadius {}, stiffness {}, gravity {} × {}, drag {}",
                    node(j.joint),
                    j.hit_radius,
                    j.stiffness,
                    j.gravity_power,
                    v(j.gravity_dir),
                    j.drag_force
                );
            }
        }
        for (i, g) in b.collider_groups.iter().enumerate() {
            let _ = writeln!(
                o,
                "  collider group {i} '{}': colliders {:?}",
                g.name, g.colliders
            );
        }
        for (i, c) in b.colliders.iter().enumerate() {
            let shape = match c.shape {
                VrmShape::Sphere {
                    offset,
                    radius,
                    inside,
                } => format!(
                    "{}sphere at {} radius {radius}",
                    if inside { "inside " } else { "" },
                    v(offset)
                ),
                VrmShape::Capsule {
                    offset,
                    tail,
                    radius,
                    inside,
                } => format!(
                    "{}capsule {} → {} radius {radius}",
                    if inside { "inside " } else { "" },
                    v(offset),
                    v(tail)
                ),
                VrmShape::Plane { offset, normal } => {
                    format!("plane through {} normal {}", v(offset), v(normal))
                }
            };
            let _ = writeln!(o, "  collider {i} on {}: {shape}", node(c.joint));
        }
    }
    if !m.warnings.is_empty() {
        let _ = writeln!(o, "\nWarnings:");
        for w in &m.warnings {
            let _ = writeln!(o, "  - {w}");
        }
    }
    o
}
