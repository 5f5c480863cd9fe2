//! Level meshes and skinned bodies added to a document built from a skeleton: each shape
//! read back where its collider is, a limb's vertices skinned by the written weights and
//! inverse bind matrices land on the posed bone, and bad parts are refused by name.

use glam::{Quat, Vec3};
use tassel::controller::{Level, LevelCollider, LevelShape};
use tassel::{Pose, SkeletonBuilder, Transform};
use tassel_gltf::{
    export_glb, load_slice, Body, BoneMesh, ExportSource, LevelPart, Limb, Material, Sheet,
};

fn colliders() -> Vec<LevelCollider> {
    vec![
        LevelCollider::new(
            "box",
            LevelShape::Box {
                half_extents: Vec3::new(1.0, 0.5, 2.0),
            },
            Vec3::new(3.0, 0.5, -1.0),
        )
        .rotated(Quat::from_rotation_y(0.4)),
        LevelCollider::new(
            "ball",
            LevelShape::Sphere { radius: 0.7 },
            Vec3::new(0.0, 2.0, 5.0),
        ),
        LevelCollider::new(
            "post",
            LevelShape::Capsule {
                half_height: 1.0,
                radius: 0.25,
            },
            Vec3::new(-2.0, 1.25, 0.0),
        )
        .rotated(Quat::from_rotation_x(0.3)),
        LevelCollider::new(
            "ramp",
            LevelShape::Ramp {
                width: 2.0,
                length: 3.0,
                height: 1.0,
            },
            Vec3::new(0.0, 0.0, 10.0),
        )
        .rotated(Quat::from_rotation_y(std::f32::consts::PI)),
        LevelCollider::new(
            "rock",
            LevelShape::TriMesh {
                vertices: vec![
                    Vec3::new(-1.0, 0.0, -1.0),
                    Vec3::new(1.0, 0.0, -1.0),
                    Vec3::new(0.0, 0.0, 1.0),
                    Vec3::new(0.0, 1.5, 0.0),
                ],
                indices: vec![[0, 3, 1], [1, 3, 2], [2, 3, 0]],
            },
            Vec3::new(5.0, 0.0, 5.0),
        ),
    ]
}

#[test]
fn level_meshes_span_their_colliders() {
    let mut sk = SkeletonBuilder::new();
    sk.add("root", None, Transform::IDENTITY);
    let (sk, _) = sk.build().unwrap();
    let mut src = ExportSource::from_skeleton(&sk, BoneMesh::None);
    let cs = colliders();
    let materials = [Material::srgb("grey", [128, 128, 128])];
    let parts: Vec<LevelPart> = cs
        .iter()
        .map(|c| LevelPart {
            collider: c,
            material: 0,
        })
        .collect();
    let nodes = src.add_level(&parts, &materials).unwrap();
    let glb = export_glb(&src, &[]).unwrap();
    let model = load_slice(&glb, None, "level").unwrap();
    let level = Level::new(cs.clone()).unwrap();
    for (k, c) in cs.iter().enumerate() {
        let inst = model.meshes.iter().find(|m| m.node == nodes[k]).unwrap();
        let (lo, hi) = inst.vertices.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &v| (lo.min(v), hi.max(v)),
        );
        // The controller's own bounds, from its primitives (a turned capsule's bounds
        // are its two end spheres'; the 12-sided mesh reaches them within its
        // flattening, 1 − cos 15° of the radius, on axes that are not the collider's).
        let (blo, bhi) = level.bounds(k).unwrap();
        let tol = match c.shape {
            LevelShape::Capsule { radius, .. } => radius * (1.0 - 15f32.to_radians().cos()) + 1e-5,
            _ => 1e-5,
        };
        assert!(
            lo.abs_diff_eq(blo, tol) && hi.abs_diff_eq(bhi, tol),
            "{}: {lo}..{hi} vs {blo}..{bhi}",
            c.name
        );
        // Every vertex on the collider's surface: no deeper than rounding.
        for v in &inst.vertices {
            let d = level.capsule_penetration(1e-4, 0.0, *v, Quat::IDENTITY);
            assert!(d <= 1.1e-4, "{}: vertex {v} {d} m inside", c.name);
        }
    }
    // A material index out of range is refused, naming the part.
    let mut src = ExportSource::from_skeleton(&sk, BoneMesh::None);
    let bad = [LevelPart {
        collider: &cs[0],
        material: 3,
    }];
    let before = src.json.clone();
    let e = src.add_level(&bad, &materials).unwrap_err().to_string();
    assert!(e.contains("'box'") && e.contains("material 3"), "{e}");
    // A NaN placement (it would be written as null) is refused too, and nothing of the
    // level before it is written.
    let mut nan = cs[4].clone();
    nan.position.y = f32::NAN;
    let bad = [
        LevelPart {
            collider: &cs[0],
            material: 0,
        },
        LevelPart {
            collider: &nan,
            material: 0,
        },
    ];
    let e = src.add_level(&bad, &materials).unwrap_err().to_string();
    assert!(e.contains("'rock'") && e.contains("finite"), "{e}");
    assert_eq!(src.json, before);
}

/// A two-bone arm: shoulder at the origin, elbow 1 m along +x, a limb on each.
fn arm() -> (tassel::Skeleton, Body) {
    let mut b = SkeletonBuilder::new();
    let s = b.add("shoulder", None, Transform::IDENTITY);
    let e = b.add(
        "elbow",
        Some(s),
        Transform::from_translation(Vec3::new(1.0, 0.0, 0.0)),
    );
    let sk = b.build().unwrap().0;
    let body = Body {
        materials: vec![Material::srgb("skin", [200, 160, 140])],
        limbs: vec![
            Limb {
                joint: s,
                tip: Vec3::X,
                radius: [0.1, 0.1],
                material: 0,
            },
            Limb {
                joint: e,
                tip: Vec3::new(2.0, 0.0, 0.0),
                radius: [0.1, 0.1],
                material: 0,
            },
        ],
        sheets: vec![],
    };
    (sk, body)
}

#[test]
fn a_skinned_limb_follows_its_bone_and_bends_smoothly_at_the_joint() {
    let (sk, body) = arm();
    let mut src = ExportSource::from_skeleton(&sk, BoneMesh::None);
    let node = src.add_body(&sk, &body).unwrap();
    let glb = export_glb(&src, &[]).unwrap();
    // Read the written skin back with the gltf crate and skin by glTF's formula:
    // Σ w · (joint world · inverse bind) · bind position.
    let g = gltf::Gltf::from_slice(&glb).unwrap();
    let bin = g.blob.as_deref().unwrap();
    let n = g.nodes().nth(node).unwrap();
    let skin = n.skin().unwrap();
    let ibm: Vec<glam::Mat4> = skin
        .reader(|_| Some(bin))
        .read_inverse_bind_matrices()
        .unwrap()
        .map(|m| glam::Mat4::from_cols_array_2d(&m))
        .collect();
    // Bend the elbow 90° about z.
    let mut pose = Pose::rest(&sk);
    pose.locals[1].rotation = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    pose.update_models(&sk, &Transform::IDENTITY).unwrap();
    let world: Vec<glam::Mat4> = pose.models.iter().map(|m| m.to_mat4()).collect();
    let prim = n.mesh().unwrap().primitives().next().unwrap();
    let r = prim.reader(|_| Some(bin));
    let pos: Vec<Vec3> = r.read_positions().unwrap().map(Vec3::from).collect();
    let joints: Vec<[u16; 4]> = r.read_joints(0).unwrap().into_u16().collect();
    let weights: Vec<[f32; 4]> = r.read_weights(0).unwrap().into_f32().collect();
    let mut shared = 0;
    for ((p, j), w) in pos.iter().zip(&joints).zip(&weights) {
        assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        let skinned: Vec3 = (0..4)
            .map(|k| w[k] * (world[j[k] as usize] * ibm[j[k] as usize]).transform_point3(*p))
            .sum();
        if w.iter().any(|&x| (x - 0.5).abs() < 1e-6) {
            shared += 1;
        }
        // Far from the elbow a vertex moves with its own bone exactly: the upper arm's
        // stays put, the forearm's turns to run along +y from (1, 0, 0).
        if p.x < 0.7 {
            assert!(skinned.abs_diff_eq(*p, 1e-5), "{p} → {skinned}");
        } else if p.x > 1.3 {
            let bent = Vec3::new(1.0 - p.y, p.x - 1.0, p.z);
            assert!(
                skinned.abs_diff_eq(bent, 1e-5),
                "{p} → {skinned}, want {bent}"
            );
        } else {
            // Near the elbow the skin lies between the two bones: within the tube's
            // radius of the bent arm's corner region, never flung away.
            assert!((skinned - Vec3::X).length() < 0.45, "{p} → {skinned}");
        }
    }
    // The rings at the elbow end of the upper arm and the start of the forearm (and their
    // caps) are shared half and half.
    assert!(shared >= 2 * 12, "{shared} vertices shared at the elbow");
}

#[test]
fn bad_bodies_are_refused_by_name() {
    let (sk, body) = arm();
    let cases: Vec<(Body, &str)> = vec![
        (
            Body {
                limbs: vec![Limb {
                    radius: [-0.1, 0.1],
                    ..body.limbs[0].clone()
                }],
                ..body.clone()
            },
            "limb 0 (shoulder)",
        ),
        (
            Body {
                limbs: vec![Limb {
                    joint: 9,
                    ..body.limbs[0].clone()
                }],
                ..body.clone()
            },
            "joint 9 of 2",
        ),
        (
            Body {
                sheets: vec![Sheet {
                    columns: vec![vec![(0, Vec3::ZERO), (1, Vec3::X)], vec![(0, Vec3::Y)]],
                    closed: false,
                    material: 0,
                }],
                ..body.clone()
            },
            "sheet 0",
        ),
        (
            Body {
                limbs: vec![],
                ..body.clone()
            },
            "no limbs and no sheets",
        ),
    ];
    for (b, want) in cases {
        let mut src = ExportSource::from_skeleton(&sk, BoneMesh::None);
        let before = src.json.clone();
        let e = src.add_body(&sk, &b).unwrap_err().to_string();
        assert!(e.contains(want), "{e} (wanted {want})");
        // Checked before anything is written.
        assert_eq!(src.json, before);
    }
}
