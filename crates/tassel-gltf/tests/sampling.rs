//! The sampling job (with its key cursor) on real clips, against values computed by hand
//! from the files' keyframes.

mod common;

use glam::{Quat, Vec4};
use tassel::anim::{Playback, SamplingCursor, SamplingJob};
use tassel_gltf::load;

fn mid(a: Quat, b: Quat) -> Quat {
    // Slerp at one half is the normalised sum (same hemisphere).
    Quat::from_vec4(Vec4::from(a) + Vec4::from(b)).normalize()
}

#[test]
fn rigged_figure_neck_at_half_time() {
    let Some(path) = common::testdata("gltf/RiggedFigure.glb") else {
        return;
    };
    let m = load(&path).unwrap();
    // neck_joint_1 (node 19): rotation keys at 0 s and 1.25 s, read off the file.
    let q0 = Quat::from_xyzw(-0.727_128, 6.392_767e-11, -1.964_863e-11, -0.686_502);
    let q1 = Quat::from_xyzw(-0.635_452_7, 1.204_559_4e-13, 1.019_438_2e-13, -0.772_14);
    let j = m.node_to_joint[19];
    assert_eq!(m.skeleton.name(j), "neck_joint_1");
    let clip = &m.clips[0];
    let mut cursor = SamplingCursor::new(clip);
    let mut locals = m.skeleton.rest().to_vec();
    // Forward in small steps (the cursor walks), then the chosen time.
    for k in 0..=50 {
        let t = k as f32 * 0.0125;
        SamplingJob {
            clip,
            cursor: &mut cursor,
            time: t,
            playback: Playback::Clamp,
            locals: &mut locals,
        }
        .run()
        .unwrap();
    }
    assert!(
        locals[j].rotation.dot(mid(q0, q1)).abs() > 1.0 - 1e-6,
        "{}",
        locals[j].rotation
    );
    // By ratio, looping past the end: ratio 1.5 of a looped clip is half way again.
    let t = SamplingJob::time_of_ratio(clip, 1.5);
    SamplingJob {
        clip,
        cursor: &mut cursor,
        time: t,
        playback: Playback::Loop,
        locals: &mut locals,
    }
    .run()
    .unwrap();
    assert!(locals[j].rotation.dot(mid(q0, q1)).abs() > 1.0 - 1e-6);
}

#[test]
fn fox_survey_cursor_agrees_with_hand_values_forward_and_back() {
    let Some(path) = common::testdata("gltf/Fox.glb") else {
        return;
    };
    let m = load(&path).unwrap();
    let clip = &m.clips[0];
    let head = m.node_to_joint[8];
    // b_Head_05 keys 0 and 1 (t = 0 and 1/24 s), read off the file.
    let k0 = Quat::from_xyzw(-0.100_036_45, -0.313_690_57, -0.407_602_5, 0.851_734_2);
    let k1 = Quat::from_xyzw(-0.100_419_14, -0.310_795_37, -0.410_886_97, 0.851_172_2);
    let mut cursor = SamplingCursor::new(clip);
    let mut locals = m.skeleton.rest().to_vec();
    // Play forward to the end, then jump back to the start: the cursor must search back.
    for k in 0..=100 {
        let t = k as f32 * clip.duration / 100.0;
        SamplingJob {
            clip,
            cursor: &mut cursor,
            time: t,
            playback: Playback::Clamp,
            locals: &mut locals,
        }
        .run()
        .unwrap();
    }
    SamplingJob {
        clip,
        cursor: &mut cursor,
        time: 1.0 / 48.0,
        playback: Playback::Clamp,
        locals: &mut locals,
    }
    .run()
    .unwrap();
    assert!(locals[head].rotation.dot(mid(k0, k1)).abs() > 1.0 - 1e-6);
}
