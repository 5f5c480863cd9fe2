//! Import of the Khronos samples, checked against facts read off the files by hand
//! (joint counts, clip names and durations from the accessors' `max`, keyframe values).

mod common;

use glam::{Quat, Vec3};
use tassel::Pose;
use tassel_gltf::{load, load_slice, GltfError};

#[test]
fn fox_skeleton_and_clips() {
    let Some(path) = common::testdata("gltf/Fox.glb") else {
        return;
    };
    let m = load(&path).unwrap();
    assert_eq!(m.skeleton.len(), 26, "26 nodes");
    assert_eq!(m.skins.len(), 1);
    assert_eq!(m.skins[0].joints.len(), 24);
    let names: Vec<&str> = m.clips.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    for (clip, dur) in m.clips.iter().zip([3.416_666_7, 0.708_333_3, 1.158_333_3]) {
        assert!(
            (clip.duration - dur).abs() < 1e-5,
            "{} {}",
            clip.name,
            clip.duration
        );
        assert_eq!(
            clip.tracks
                .iter()
                .map(|t| [
                    t.translation.is_some(),
                    t.rotation.is_some(),
                    t.scale.is_some()
                ]
                .iter()
                .filter(|b| **b)
                .count())
                .sum::<usize>(),
            21
        );
    }
    // b_Head_05 (node 8), Survey: keys 0 and 1 read from the file; halfway between them
    // slerp equals the normalised sum of the two keys.
    let k0 = Quat::from_xyzw(-0.100_036_45, -0.313_690_57, -0.407_602_5, 0.851_734_2);
    let k1 = Quat::from_xyzw(-0.100_419_14, -0.310_795_37, -0.410_886_97, 0.851_172_2);
    let expected = Quat::from_vec4(glam::Vec4::from(k0) + glam::Vec4::from(k1)).normalize();
    let head = m.node_to_joint[8];
    assert_eq!(m.skeleton.name(head), "b_Head_05");
    let mut pose = Pose::rest(&m.skeleton);
    m.clips[0].sample(0.041_666_668 / 2.0, &mut pose.locals);
    assert!(
        pose.locals[head].rotation.dot(expected).abs() > 1.0 - 1e-6,
        "{}",
        pose.locals[head].rotation
    );
    for i in 1..m.skeleton.len() {
        assert!(m.skeleton.parent(i).is_none_or(|p| p < i));
    }
}

#[test]
fn simple_skin_embedded_buffers_and_hand_slerp() {
    let Some(path) = common::testdata("gltf/SimpleSkin.gltf") else {
        return;
    };
    let m = load(&path).unwrap();
    assert_eq!(m.skeleton.len(), 3);
    assert_eq!(m.skins[0].joints.len(), 2);
    assert!((m.clips[0].duration - 5.5).abs() < 1e-6);
    // Node 2 rotation keys at 0 and 0.5 s are identity and (0, 0, 0.383, 0.924); at
    // 0.25 s slerp gives their normalised sum.
    let j = m.node_to_joint[2];
    let mut pose = Pose::rest(&m.skeleton);
    m.clips[0].sample(0.25, &mut pose.locals);
    let expected = Quat::from_xyzw(0.0, 0.0, 0.383, 1.924).normalize();
    assert!(pose.locals[j].rotation.dot(expected).abs() > 1.0 - 1e-6);
    // Inverse bind matrix of joint 1 in the tutorial: translation (0, -1, 0).
    let ibm = m.skins[0].inverse_bind[1];
    assert!(ibm
        .w_axis
        .truncate()
        .abs_diff_eq(Vec3::new(0.0, -1.0, 0.0), 1e-6));
}

#[test]
fn rigged_samples_load() {
    for (file, nodes, joints, channels, dur) in [
        ("gltf/RiggedSimple.glb", 5, 2, 3, 2.083_333),
        ("gltf/RiggedFigure.glb", 22, 19, 57, 1.25),
    ] {
        let Some(path) = common::testdata(file) else {
            return;
        };
        let m = load(&path).unwrap();
        assert_eq!(m.skeleton.len(), nodes, "{file}");
        assert_eq!(m.skins[0].joints.len(), joints, "{file}");
        let n: usize = m.clips[0]
            .tracks
            .iter()
            .map(|t| {
                t.translation.is_some() as usize
                    + t.rotation.is_some() as usize
                    + t.scale.is_some() as usize
            })
            .sum();
        assert_eq!(n, channels, "{file}");
        assert!((m.clips[0].duration - dur).abs() < 1e-5, "{file}");
    }
}

#[test]
fn cubic_and_step_samplers_from_a_file() {
    // A hand-written glTF: node 0 translation, CUBICSPLINE, keys at 0 and 1 with values
    // x = 0 and x = 2, out-tangent 0 and in-tangent 0: at 0.5 the Hermite curve gives 1.
    // Node 0 scale, STEP: 1 until 1 s, then 3.
    let floats: [f32; 2 + 18 + 6] = [
        0.0, 1.0, // times
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, // key 0: in, value, out
        0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0, 0.0, // key 1
        1.0, 1.0, 1.0, 3.0, 3.0, 3.0, // step scales
    ];
    let bytes: Vec<u8> = floats.iter().flat_map(|f| f.to_le_bytes()).collect();
    use base64::Engine;
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    );
    let doc = serde_json::json!({
        "asset": {"version": "2.0"},
        "nodes": [{"name": "n"}],
        "buffers": [{"byteLength": bytes.len(), "uri": uri}],
        "bufferViews": [{"buffer": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 72}, {"buffer": 0, "byteOffset": 80, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 6, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"}
        ],
        "animations": [{"name": "a", "samplers": [
            {"input": 0, "output": 1, "interpolation": "CUBICSPLINE"},
            {"input": 0, "output": 2, "interpolation": "STEP"}],
          "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}},
                       {"sampler": 1, "target": {"node": 0, "path": "scale"}}]}]
    });
    let m = load_slice(doc.to_string().as_bytes(), None, "hand.gltf").unwrap();
    let mut pose = Pose::rest(&m.skeleton);
    m.clips[0].sample(0.5, &mut pose.locals);
    assert!(pose.locals[0]
        .translation
        .abs_diff_eq(Vec3::new(1.0, 0.0, 0.0), 1e-6));
    assert_eq!(pose.locals[0].scale, Vec3::ONE);
    m.clips[0].sample(1.0, &mut pose.locals);
    assert_eq!(pose.locals[0].scale, Vec3::splat(3.0));
}

#[test]
fn broken_files_give_named_errors() {
    if let Some(path) = common::testdata("gltf/Fox.glb") {
        let bytes = std::fs::read(&path).unwrap();
        let e = load_slice(&bytes[..bytes.len() / 2], None, "half.glb").unwrap_err();
        assert!(matches!(e, GltfError::Invalid { .. }), "{e}");
        assert!(e.to_string().contains("half.glb"));
    }
    let cycle = r#"{"asset":{"version":"2.0"},"nodes":[{"name":"a","children":[1]},{"name":"b","children":[0]}],
                   "skins":[{"joints":[0,1]}]}"#;
    let e = load_slice(cycle.as_bytes(), None, "cycle.gltf")
        .unwrap_err()
        .to_string();
    assert!(e.contains("cycle"), "{e}");
    let e = load(std::path::Path::new("/no/such/file.glb"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("/no/such/file.glb"), "{e}");
}
