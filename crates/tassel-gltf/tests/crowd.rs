//! The crowd path on the real VRM files in ../shared/testdata/vrm/: every character of a
//! `VrmCrowd` gives the bits of its own `CharacterSim`, frame after frame, in the `spec`,
//! `three-vrm` and `fixed` (60 and 90 Hz steps) modes, with node constraints too.

mod common;

use common::{bits, input, testdata, vrm_files};
use std::sync::Arc;
use tassel::crowd::{CrowdPose, SimdUse, VrmCrowd};
use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmRig, VrmSpringBones};
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Skeleton, Transform};
use tassel_gltf::Model;

/// Five characters, 600 frames (a hitch at frame 300): every local and model transform of
/// every character the same bits in the crowd and in its own `CharacterSim`. Returns the
/// largest angle any spring joint turned away from its rest rotation (the test's own
/// check that something moved).
fn compare(
    name: &str,
    sk: &Skeleton,
    bones: &VrmSpringBones,
    (mode, step_rate): (VrmMode, f32),
) -> f32 {
    let options = VrmOptions {
        mode,
        step_rate,
        ..Default::default()
    };
    let rig = Arc::new(VrmRig::new(sk, bones, options).unwrap());
    let swing = rig.links.first().and_then(|l| l.parent).unwrap_or(0);
    let mut crowd = VrmCrowd::new(Arc::new(sk.clone()), rig.clone()).unwrap();
    let n = 5;
    let mut sims: Vec<CharacterSim> = (0..n)
        .map(|_| {
            crowd.add();
            let mut sim =
                CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), bones, options)
                    .unwrap();
            // The readable reference (the lane path is tested against it in vrm_lanes.rs).
            sim.set_simd(SimdUse::Scalar);
            sim
        })
        .collect();
    let mut inputs = vec![(Transform::IDENTITY, sk.rest().to_vec()); n];
    let (mut locals, mut models) = (sk.rest().to_vec(), sk.rest().to_vec());
    let mut turned = 0.0f32;
    for f in 0..600 {
        for (i, (t, l)) in inputs.iter_mut().enumerate() {
            *t = input(sk, swing, i, f, l);
        }
        let dt = if f == 300 { 0.2 } else { 1.0 / 60.0 };
        crowd
            .frame(dt, |i| CrowdPose {
                transform: inputs[i].0,
                locals: &inputs[i].1,
            })
            .unwrap();
        for (i, sim) in sims.iter_mut().enumerate() {
            let pose = sim.frame(&inputs[i].1, inputs[i].0, dt).unwrap();
            locals.copy_from_slice(&inputs[i].1);
            crowd.write_pose(i, &mut locals, &mut models).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    (bits(&locals[j]), bits(&models[j])),
                    (bits(&pose.locals[j]), bits(&pose.models[j])),
                    "{name} {mode:?}: frame {f}, character {i}, joint '{}'",
                    sk.name(j)
                );
            }
        }
        for (k, l) in rig.links.iter().enumerate() {
            turned = turned.max(
                crowd
                    .rotation(0, k)
                    .unwrap()
                    .angle_between(l.rest_local.rotation),
            );
        }
    }
    turned
}

/// Every mode; fixed at the frame rate and at 90 Hz.
const MODES: [(VrmMode, f32); 4] = [
    (VrmMode::Spec, 60.0),
    (VrmMode::ThreeVrm, 60.0),
    (VrmMode::Fixed, 60.0),
    (VrmMode::Fixed, 90.0),
];

#[test]
fn vrm_crowd_gives_each_files_single_character_bits() {
    for path in vrm_files() {
        let model = tassel_gltf::load(&path).unwrap();
        let bones = model.vrm.clone().unwrap().springs;
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        for mode in MODES {
            let turned = compare(&name, &model.skeleton, &bones, mode);
            assert!(
                turned > 0.05,
                "{name} {mode:?}: the springs never moved ({turned} rad)"
            );
        }
    }
}

/// Node constraints (roll, aim and rotation, applied before the springs) in a crowd.
#[test]
fn vrm_crowd_applies_node_constraints_as_the_single_path_does() {
    let Some(path) = testdata("vrm/sphere-collider.gltf") else {
        return;
    };
    let bytes = std::fs::read(&path).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    json["extensionsUsed"] = serde_json::json!(["VRMC_springBone", "VRMC_node_constraint"]);
    for (node, c) in [
        (
            5,
            serde_json::json!({"roll": {"source": 1, "rollAxis": "Y", "weight": 0.7}}),
        ),
        (
            3,
            serde_json::json!({"aim": {"source": 1, "aimAxis": "NegativeY"}}),
        ),
    ] {
        json["nodes"][node]["extensions"] =
            serde_json::json!({ "VRMC_node_constraint": {"specVersion": "1.0", "constraint": c} });
    }
    let bytes = serde_json::to_vec(&json).unwrap();
    let model: Model = tassel_gltf::load_slice(&bytes, path.parent(), "edited.gltf").unwrap();
    let bones = model.vrm.clone().unwrap().springs;
    assert_eq!(bones.node_constraints.len(), 2);
    for mode in MODES {
        compare("constrained sphere-collider", &model.skeleton, &bones, mode);
    }
}
