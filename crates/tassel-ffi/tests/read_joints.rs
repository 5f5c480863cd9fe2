//! `read_joints`: the joints a frame depends on. Checked against the frame itself: two
//! copies of each VRM file of `../shared/testdata/vrm` step the same motion in every VRM
//! mode, one with the joints outside `read_joints` at rest, the other with them set to
//! something else every frame (far away, turned, scaled); the simulated joints must come
//! out bit for bit the same. And a rig that is not VRM springs alone reads every joint.

mod common;

use common::vrm_files;
use tassel::glam::Quat;
use tassel_ffi::{FlatCharacter, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;

/// The character's root at frame `f` (swaying and turning) and its animated locals: the
/// rest pose with the first two read joints turned about x.
fn input(c: &FlatCharacter, f: usize) -> ([f32; F], Vec<f32>) {
    let t = f as f32 / 60.0;
    let root = common::swaying_root(f);
    let mut locals = vec![0.0; c.joint_count() * F];
    c.rest_locals(&mut locals).unwrap();
    for (k, &j) in c.read_joints().iter().take(2).enumerate() {
        common::turn_about_x(&mut locals, j, 0.3 * (4.0 * t + k as f32).sin());
    }
    (root, locals)
}

#[test]
fn joints_outside_read_joints_change_nothing() {
    for path in vrm_files() {
        let bytes = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy();
        for mode in ["fixed", "spec", "three-vrm"] {
            let mut a = FlatCharacter::load(&bytes, None, Some(mode)).unwrap();
            let mut b = FlatCharacter::load(&bytes, None, Some(mode)).unwrap();
            let n = a.joint_count();
            let read = a.read_joints().to_vec();
            let written = a.simulated_joints().to_vec();
            assert!(
                read.windows(2).all(|w| w[0] < w[1]) && read.iter().all(|&j| j < n),
                "{name}: read joints {read:?}"
            );
            assert!(
                written.iter().all(|j| read.contains(j)),
                "{name}: a simulated joint is not read: {written:?} / {read:?}"
            );
            // These files have more nodes than their springs need: the test compares something.
            assert!(read.len() < n, "{name}: every one of {n} joints is read");
            let unread: Vec<usize> = (0..n).filter(|j| !read.contains(j)).collect();
            let mut swing = 0.0f32;
            for f in 1..=90 {
                let dt = if f == 25 { 0.25 } else { 1.0 / 60.0 };
                let (root, mut la) = input(&a, f);
                let mut lb = la.clone();
                for (k, &j) in unread.iter().enumerate() {
                    let x = (f + k) as f32;
                    let q = Quat::from_rotation_y(0.7 * x).mul_quat(Quat::from_rotation_z(0.3 * x));
                    lb[j * F..j * F + 3].copy_from_slice(&[3.0 * x, -2.0 * x, 7.0]);
                    lb[j * F + 3..j * F + 7].copy_from_slice(&q.to_array());
                    lb[j * F + 7..j * F + 10].copy_from_slice(&[2.0, 0.5, 3.0]);
                }
                let animated = la.clone();
                a.frame(&root, &mut la, dt).unwrap();
                b.frame(&root, &mut lb, dt).unwrap();
                for &j in &written {
                    let (pa, pb) = (&la[j * F..j * F + F], &lb[j * F..j * F + F]);
                    assert!(
                        pa.iter().zip(pb).all(|(x, y)| x.to_bits() == y.to_bits()),
                        "{name} {mode} frame {f} joint {j}: {pa:?} with the unread joints at rest, {pb:?} with them moved"
                    );
                    let qa = Quat::from_slice(&pa[3..7]);
                    let qr = Quat::from_slice(&animated[j * F + 3..j * F + 7]);
                    swing = swing.max(qa.angle_between(qr));
                }
            }
            // The springs moved: the frames compared were not all the rest pose.
            assert!(
                swing > 0.01,
                "{name} {mode}: the springs swung only {swing} rad"
            );
        }
    }
}

#[test]
fn a_rig_beyond_vrm_springs_reads_every_joint() {
    let glb = common::builtin_glb();
    let rig = tassel::builtin::character().rig.to_toml_string().unwrap();
    let c = FlatCharacter::load(&glb, Some(&rig), None).unwrap();
    assert_eq!(
        c.read_joints(),
        (0..c.joint_count()).collect::<Vec<_>>().as_slice()
    );
}
