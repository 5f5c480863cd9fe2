//! How the built-in character is dressed: its body (tubes per bone, thin strands for the
//! simulated hair, tail and charm, a sheet for the skirt) and a colour per simulated
//! group. Data only: the meshes are made by [`ExportSource::add_body`](crate::ExportSource::add_body).

use crate::scene::{Body, Limb, Material, Sheet};
use glam::Vec3;
use tassel::{Pose, Skeleton};

/// Colour of a simulated group (chain, cloth or rope name) in the picture and the file.
pub fn group_color(name: &str) -> [u8; 3] {
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

/// Where a limb ends: at another bone, or an offset from its own joint (model space).
enum End {
    Bone(String),
    Offset(Vec3),
}

const SKIN: usize = 0;
const SHIRT: usize = 1;
const TROUSERS: usize = 2;
const SHOES: usize = 3;

/// The built-in character's body: a tapered tube per unsimulated bone (skin, shirt, trousers, shoes), a strand
/// along every simulated group of `strands` (name, joints from the one it hangs from; one
/// material each, from index 4 on, in their order) and a sheet through the skirt's bones.
pub fn builtin_body(sk: &Skeleton, strands: &[(String, Vec<usize>)]) -> Body {
    let rest = Pose::rest(sk);
    let at = |j: usize| rest.models[j].translation;
    let mut materials = vec![
        Material::srgb("skin", [232, 190, 160]),
        Material::srgb("shirt", [80, 100, 150]),
        Material::srgb("trousers", [60, 62, 74]),
        Material::srgb("shoes", [40, 36, 34]),
    ];
    let mut limbs = Vec::new();
    let mut add = |bone: &str, end: End, radius: [f32; 2], material: usize| {
        let Some(j) = sk.find(bone) else { return };
        let tip = match end {
            End::Bone(e) => match sk.find(&e) {
                Some(e) => at(e),
                None => return,
            },
            End::Offset(offset) => at(j) + offset,
        };
        limbs.push(Limb {
            joint: j,
            tip,
            radius,
            material,
        });
    };
    let bone = |n: &str| End::Bone(n.to_string());
    add("hips", bone("spine"), [0.13, 0.12], TROUSERS);
    add("spine", bone("chest"), [0.12, 0.13], SHIRT);
    add("chest", bone("neck"), [0.13, 0.1], SHIRT);
    add("neck", bone("head"), [0.045, 0.045], SKIN);
    add(
        "head",
        End::Offset(Vec3::new(0.0, 0.12, 0.01)),
        [0.09, 0.1],
        SKIN,
    );
    for side in ["l", "r"] {
        let b = |n: &str| format!("{n}_{side}");
        let end = |n: &str| End::Bone(b(n));
        let bust = End::Offset(Vec3::new(0.0, -0.01, 0.01));
        add(&b("chest"), bust, [0.055, 0.05], SHIRT);
        add("chest", end("shoulder"), [0.07, 0.055], SHIRT);
        add(&b("shoulder"), end("upper_arm"), [0.055, 0.05], SHIRT);
        add(&b("upper_arm"), end("lower_arm"), [0.048, 0.04], SHIRT);
        add(&b("lower_arm"), end("hand"), [0.036, 0.03], SKIN);
        let palm = End::Offset(Vec3::new(0.0, -0.07, 0.0));
        add(&b("hand"), palm, [0.032, 0.028], SKIN);
        add(&b("thigh"), end("shin"), [0.075, 0.055], TROUSERS);
        add(&b("shin"), end("foot"), [0.055, 0.042], TROUSERS);
        add(&b("foot"), end("toe"), [0.042, 0.036], SHOES);
    }
    // Strands: from each joint of a simulated group to the next; the last one goes on by
    // its bone's length. The first joint is where the strand is rooted (not simulated).
    for (name, joints) in strands {
        let m = materials.len();
        let mut mat = Material::srgb(name.clone(), group_color(name));
        mat.double_sided = name == "skirt";
        materials.push(mat);
        if name == "skirt" {
            continue;
        }
        let r = match name.split('_').next().unwrap_or("") {
            "ponytail" => [0.03, 0.012],
            "tail" => [0.028, 0.01],
            "charm" => [0.008, 0.008],
            _ => [0.014, 0.008],
        };
        let n = joints.len();
        for (k, &j) in joints.iter().enumerate() {
            let tip = match joints.get(k + 1) {
                Some(&c) => at(c),
                None => match sk.parent(j) {
                    Some(p) => at(j) + (at(j) - at(p)),
                    None => continue,
                },
            };
            let t = |i: usize| i as f32 / n as f32;
            let radius = [r[0] + (r[1] - r[0]) * t(k), r[0] + (r[1] - r[0]) * t(k + 1)];
            // The charm ends in a tassel.
            let radius = if name == "charm" && k + 1 == n {
                [0.012, 0.028]
            } else {
                radius
            };
            limbs.push(Limb {
                joint: j,
                tip,
                radius,
                material: m,
            });
        }
    }
    let mut sheets = Vec::new();
    if let Some(m) = strands.iter().position(|(n, _)| n == "skirt") {
        // Columns skirt_K_0..3 and on by the last bone's length, around the waist.
        let mut columns = Vec::new();
        for k in 0.. {
            let mut col = Vec::new();
            for i in 0.. {
                match sk.find(&format!("skirt_{k}_{i}")) {
                    Some(j) => col.push((j, at(j))),
                    None => break,
                }
            }
            if col.len() < 2 {
                break;
            }
            let (j, last) = col[col.len() - 1];
            let before = col[col.len() - 2].1;
            col.push((j, last + (last - before)));
            columns.push(col);
        }
        if columns.len() >= 2 {
            sheets.push(Sheet {
                columns,
                closed: true,
                material: 4 + m,
            });
        }
    }
    Body {
        materials,
        limbs,
        sheets,
    }
}
