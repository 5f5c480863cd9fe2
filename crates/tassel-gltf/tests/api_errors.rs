//! The public functions return typed errors a caller can match on, not strings.

use serde_json::json;
use tassel::builtin;
use tassel::dynamics::vrm::VrmTail;
use tassel::CharacterSim;
use tassel_gltf::{key_times, play, read_spring_bones, BakeOptions, GltfError, PlayError};

fn builtin_sim() -> (CharacterSim, tassel::anim::Clip) {
    let c = builtin::character();
    let clip = c.clips[0].clone();
    (CharacterSim::new(c.skeleton, &c.rig).unwrap(), clip)
}

/// The caller's own error type comes back unchanged, after the frame that raised it.
#[test]
fn play_returns_the_callers_error_unchanged() {
    #[derive(Debug, PartialEq)]
    struct Stop(usize);
    let (mut sim, clip) = builtin_sim();
    let options = BakeOptions {
        warmup: 0.0,
        ..Default::default()
    };
    let times = key_times(1.0, 60.0);
    let mut seen = 0;
    let r = play(&mut sim, Some(&clip), &times, &options, &mut |f| {
        seen += 1;
        if f.index == 3 {
            Err(Stop(f.index))
        } else {
            Ok(())
        }
    });
    match r {
        Err(PlayError::Frame(e)) => assert_eq!(e, Stop(3)),
        other => panic!("expected the callback's error, got {other:?}"),
    }
    assert_eq!(seen, 4, "the run stops at the failing frame");
}

#[test]
fn play_rejects_bad_options_before_running() {
    let (mut sim, clip) = builtin_sim();
    let options = BakeOptions {
        fps: f32::NAN,
        ..Default::default()
    };
    let mut called = false;
    let r = play(&mut sim, Some(&clip), &[0.0], &options, &mut |_| {
        called = true;
        Ok::<(), String>(())
    });
    match r {
        Err(PlayError::Options(GltfError::Invalid { message, .. })) => {
            assert!(message.contains("fps"), "{message}")
        }
        other => panic!("expected an options error, got {other:?}"),
    }
    assert!(!called);
}

#[test]
fn read_spring_bones_names_the_bad_entry_in_a_typed_error() {
    // Two nodes (joints 0 and 1); the spring's second joint points at node 7.
    let doc = json!({
        "asset": {"version": "2.0"},
        "nodes": [{"name": "root", "children": [1]}, {"name": "hair"}],
        "extensions": {"VRMC_springBone": {
            "specVersion": "1.0",
            "springs": [{"name": "hair", "joints": [{"node": 1}, {"node": 7}]}]
        }}
    });
    match read_spring_bones(&doc, &[0, 1], &mut Vec::new()) {
        Err(GltfError::Invalid { message, .. }) => {
            assert!(message.contains("spring bones"), "{message}");
            assert!(message.contains('7'), "does not name the node: {message}");
        }
        other => panic!("expected GltfError::Invalid, got {other:?}"),
    }
    // The same document with the joint in range reads.
    let mut good = doc.clone();
    good["extensions"]["VRMC_springBone"]["springs"][0]["joints"] =
        json!([{"node": 0}, {"node": 1}]);
    let info = read_spring_bones(&good, &[0, 1], &mut Vec::new())
        .unwrap()
        .expect("springs");
    // By the specification the last joint is only the tail of the one before it.
    let joints = &info.springs.springs[0].joints;
    assert_eq!(joints.len(), 1);
    assert_eq!(joints[0].joint, 0);
    assert_eq!(joints[0].tail, VrmTail::Joint(1));
}
