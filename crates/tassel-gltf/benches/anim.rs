//! Sampling and blending speed, per joint: the Fox clips (from ../shared/testdata, when
//! present) and a synthetic 128-joint clip (LINEAR T/R/S keys at 30 Hz, 2 s).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Quat, Vec3};
use std::hint::black_box;
use tassel::anim::{
    BlendJob, BlendLayer, Channel, Clip, Interpolation, JointTrack, Playback, SamplingCursor,
    SamplingJob,
};
use tassel::Transform;

fn synthetic(joints: usize) -> Clip {
    let times: Vec<f32> = (0..=60).map(|k| k as f32 / 30.0).collect();
    let ch = |f: &dyn Fn(f32) -> Vec3| Channel {
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: times.iter().map(|&t| f(t)).collect(),
    };
    let tracks = (0..joints)
        .map(|j| JointTrack {
            joint: j,
            translation: Some(ch(&|t| Vec3::new(t, 0.1 * j as f32, 0.0))),
            rotation: Some(Channel {
                interpolation: Interpolation::Linear,
                times: times.clone(),
                values: times
                    .iter()
                    .map(|&t| Quat::from_rotation_y(t + j as f32))
                    .collect(),
            }),
            scale: Some(ch(&|t| Vec3::splat(1.0 + 0.1 * t))),
        })
        .collect();
    Clip {
        name: "synthetic".into(),
        duration: 2.0,
        tracks,
    }
}

fn bench_set(c: &mut Criterion, label: &str, clips: &[Clip], joints: usize) {
    let rest = vec![Transform::IDENTITY; joints];
    let mut g = c.benchmark_group(format!("anim/{label}"));
    g.throughput(Throughput::Elements(joints as u64));
    for clip in clips {
        let mut cursor = SamplingCursor::new(clip);
        let mut out = rest.clone();
        let mut t = 0.0f32;
        g.bench_function(format!("sample_{}", clip.name), |b| {
            b.iter(|| {
                t += 1.0 / 60.0;
                SamplingJob {
                    clip,
                    cursor: &mut cursor,
                    time: t,
                    playback: Playback::Loop,
                    locals: &mut out,
                }
                .run()
                .unwrap();
                black_box(&out);
            })
        });
    }
    let a: Vec<Transform> = (0..joints)
        .map(|j| Transform::from_translation(Vec3::splat(j as f32)))
        .collect();
    let bpose: Vec<Transform> = (0..joints)
        .map(|j| Transform::from_translation_rotation(Vec3::X, Quat::from_rotation_z(j as f32)))
        .collect();
    let cpose: Vec<Transform> = (0..joints)
        .map(|j| Transform::from_translation_rotation(Vec3::Y, Quat::from_rotation_x(j as f32)))
        .collect();
    let mut out = rest.clone();
    g.bench_function("blend_3_layers", |b| {
        b.iter(|| {
            let layers = [
                BlendLayer {
                    locals: &a,
                    weight: 0.5,
                    mask: None,
                },
                BlendLayer {
                    locals: &bpose,
                    weight: 0.3,
                    mask: None,
                },
                BlendLayer {
                    locals: &cpose,
                    weight: 0.2,
                    mask: None,
                },
            ];
            BlendJob {
                rest: &rest,
                layers: &layers,
                additive: &[],
                out: &mut out,
            }
            .run()
            .unwrap();
            black_box(&out);
        })
    });
    g.finish();
}

fn anim(c: &mut Criterion) {
    let fox = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/testdata/gltf/Fox.glb");
    match tassel_gltf::load(&fox) {
        Ok(m) => bench_set(c, "fox", &m.clips, m.skeleton.len()),
        Err(e) => eprintln!("SKIPPED the Fox benches: {e}"),
    }
    bench_set(c, "synthetic128", &[synthetic(128)], 128);
}

criterion_group!(benches, anim);
criterion_main!(benches);
