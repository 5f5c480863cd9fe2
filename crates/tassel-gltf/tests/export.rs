//! Export: files written from an input document keep its meshes, skins and other clips,
//! carry the baked clip, and pass the Khronos validator with zero errors.

mod common;

use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Transform};
use tassel_gltf::{export_glb, load, load_slice, BakedClip, BakedTrack};

fn json_of(glb: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

#[test]
fn fox_with_a_simulated_tail_round_trips_and_validates() {
    let Some(path) = common::testdata("gltf/Fox.glb") else {
        return;
    };
    let model = load(&path).unwrap();
    let rig = RigSettings::from_toml_str(
        "[[chain]]\nname = \"tail\"\nroot = \"b_Tail01_012\"\nradius = 1.0\ngravity = [0.0, -300.0, 0.0]\nteleport_distance = 0.0\n",
    )
    .unwrap();
    let mut sim = CharacterSim::new(model.skeleton.clone(), &rig).unwrap();
    let clip = &model.clips[0];
    let fps = 30.0;
    let frames = (clip.duration * fps).floor() as usize;
    let tail: Vec<usize> = (0..model.skeleton.len())
        .filter(|&j| model.skeleton.name(j).starts_with("b_Tail"))
        .collect();
    assert!(tail.len() >= 2, "the fox has tail joints");
    let mut keys: Vec<Vec<glam::Quat>> = vec![Vec::new(); model.skeleton.len()];
    let mut times = Vec::new();
    for f in 0..=frames {
        let t = f as f32 / fps;
        let mut locals = model.skeleton.rest().to_vec();
        clip.sample(t, &mut locals);
        let pose = sim
            .frame(
                &locals,
                Transform::IDENTITY,
                if f == 0 { 0.0 } else { 1.0 / fps },
            )
            .unwrap();
        for j in 0..model.skeleton.len() {
            keys[j].push(pose.locals[j].rotation);
        }
        times.push(t);
    }
    let tracks: Vec<BakedTrack> = (0..model.skeleton.len())
        .map(|j| BakedTrack {
            node: model.joint_to_node[j],
            rotations: Some(keys[j].clone()),
            ..Default::default()
        })
        .collect();
    let baked = BakedClip {
        name: clip.name.clone(),
        times,
        tracks,
        merge_into: None,
    };
    let glb = export_glb(&model.source, &[baked]).unwrap();

    let input = &model.source.json;
    let out = json_of(&glb);
    for key in ["meshes", "skins", "materials", "textures", "images"] {
        assert_eq!(
            out[key].as_array().map(|a| a.len()),
            input[key].as_array().map(|a| a.len()),
            "{key}"
        );
    }
    let names: Vec<&str> = out["animations"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["name"].as_str().unwrap())
        .collect();
    assert_eq!(names.len(), 3);
    assert!(names.contains(&"Walk") && names.contains(&"Run") && names.contains(&"Survey"));

    // Reload: the baked Survey has the simulated tail rotations, other clips unchanged.
    let again = load_slice(&glb, None, "baked.glb").unwrap();
    let survey = again.clips.iter().find(|c| c.name == "Survey").unwrap();
    let mut a = again.skeleton.rest().to_vec();
    survey.sample(2.0, &mut a);
    let mut orig = model.skeleton.rest().to_vec();
    clip.sample(2.0, &mut orig);
    let differs = tail.iter().any(|&j| {
        let jj = again.node_to_joint[model.joint_to_node[j]];
        a[jj].rotation.dot(orig[j].rotation).abs() < 0.9999
    });
    assert!(
        differs,
        "the tail keys equal the input's: nothing was simulated"
    );
    let walk_in = model.clips.iter().find(|c| c.name == "Walk").unwrap();
    let walk_out = again.clips.iter().find(|c| c.name == "Walk").unwrap();
    assert_eq!(walk_in.tracks.len(), walk_out.tracks.len());

    let file = std::env::temp_dir().join(format!("tassel-fox-{}.glb", std::process::id()));
    std::fs::write(&file, &glb).unwrap();
    if let Some((errors, report)) = common::validate(&file) {
        assert_eq!(errors, 0, "{report}");
    }
    let _ = std::fs::remove_file(file);
}

#[test]
fn gltf_with_embedded_buffers_exports_as_valid_glb() {
    let Some(path) = common::testdata("gltf/SimpleSkin.gltf") else {
        return;
    };
    let model = load(&path).unwrap();
    let glb = export_glb(&model.source, &[]).unwrap();
    let out = json_of(&glb);
    assert_eq!(out["buffers"].as_array().unwrap().len(), 1);
    assert!(out["buffers"][0].get("uri").is_none());
    let again = load_slice(&glb, None, "simple.glb").unwrap();
    assert_eq!(again.skeleton.len(), model.skeleton.len());
    assert_eq!(again.clips[0].duration, model.clips[0].duration);
    let file = std::env::temp_dir().join(format!("tassel-simple-{}.glb", std::process::id()));
    std::fs::write(&file, &glb).unwrap();
    if let Some((errors, report)) = common::validate(&file) {
        assert_eq!(errors, 0, "{report}");
    }
    let _ = std::fs::remove_file(file);
}

#[test]
fn bad_clips_are_rejected() {
    let sk = tassel::builtin::character().skeleton;
    let src = tassel_gltf::ExportSource::from_skeleton(&sk, tassel_gltf::BoneMesh::None);
    let clip = |times: Vec<f32>, n: usize| BakedClip {
        name: "x".into(),
        times,
        tracks: vec![BakedTrack {
            node: 0,
            translations: Some(vec![glam::Vec3::ZERO; n]),
            ..Default::default()
        }],
        merge_into: None,
    };
    assert!(
        export_glb(&src, &[clip(vec![0.0, 0.0], 2)]).is_err(),
        "non-increasing times"
    );
    assert!(
        export_glb(&src, &[clip(vec![0.0, 1.0], 3)]).is_err(),
        "key count mismatch"
    );
    let mut nan = clip(vec![0.0, 1.0], 2);
    nan.tracks[0].translations = Some(vec![glam::Vec3::NAN; 2]);
    assert!(export_glb(&src, &[nan]).is_err(), "NaN keys");
    assert!(export_glb(&src, &[clip(vec![0.0, 1.0], 2)]).is_ok());
}
