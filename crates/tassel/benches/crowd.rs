//! Criterion bench: one 60 Hz frame of 64 bench characters (16 chains × 8 joints as VRM
//! springs, 8 colliders, spec mode) through the crowd path and, in the same run, through
//! one `CharacterSim` each (the single-character reference); the crowd path also with AVX2
//! forbidden. The same for the bench character's chains (fixed mode, 60 Hz) through
//! `ChainCrowd`. Single thread. Throughput is reported per simulated joint.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;
use std::sync::Arc;
use tassel::crowd::{ChainCrowd, CrowdPose, SimdUse, VrmCrowd};
use tassel::dynamics::chain::ChainRig;
use tassel::dynamics::vrm::{VrmOptions, VrmRig};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Transform};

const N: usize = 64;

fn at(f: u32, i: usize) -> Transform {
    let t = f as f32 / 60.0 + 0.37 * i as f32;
    Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t))
}

fn vrm_crowd(c: &mut Criterion) {
    let (sk, bones) = builtin::bench_vrm(16, 8, 8);
    let options = VrmOptions::spec();
    let rig = Arc::new(VrmRig::new(&sk, &bones, options).unwrap());
    let rest = sk.rest().to_vec();
    let joints = (N * rig.links.len()) as u64;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("vrm_crowd_64");
    g.throughput(Throughput::Elements(joints));
    let mut f = 0u32;
    // The widest lanes the CPU has, AVX2 at most, and the baseline SSE2 path: the same
    // bits.
    for (name, simd) in [
        ("crowd_path", SimdUse::Auto),
        ("crowd_path_avx2", SimdUse::Avx2),
        ("crowd_path_sse2", SimdUse::Portable),
    ] {
        let mut crowd = VrmCrowd::new(Arc::new(sk.clone()), rig.clone()).unwrap();
        crowd.set_simd(simd);
        for _ in 0..N {
            crowd.add();
        }
        g.bench_function(name, |b| {
            b.iter(|| {
                f += 1;
                pool.install(|| {
                    crowd
                        .frame(1.0 / 60.0, |i| CrowdPose {
                            transform: at(f, i),
                            locals: &rest,
                        })
                        .unwrap()
                });
                black_box(crowd.rotation(0, 0));
            })
        });
    }
    let mut sims: Vec<CharacterSim> = (0..N)
        .map(|_| {
            CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), &bones, options).unwrap()
        })
        .collect();
    g.bench_function("single_character_path", |b| {
        b.iter(|| {
            f += 1;
            for (i, sim) in sims.iter_mut().enumerate() {
                black_box(sim.frame(black_box(&rest), at(f, i), 1.0 / 60.0).unwrap());
            }
        })
    });
    g.finish();
}

fn chain_crowd(c: &mut Criterion) {
    let (sk, settings) = builtin::bench_character(16, 8, 8);
    let rig = Arc::new(ChainRig::new(&sk, &settings).unwrap());
    let rest = sk.rest().to_vec();
    let joints = (N * (rig.point_count() - 16)) as u64; // chain roots are not simulated
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut g = c.benchmark_group("chain_crowd_64");
    g.throughput(Throughput::Elements(joints));
    let mut f = 0u32;
    let mut crowd = ChainCrowd::new(Arc::new(sk.clone()), rig.clone()).unwrap();
    for _ in 0..N {
        crowd.add();
    }
    g.bench_function("crowd_path", |b| {
        b.iter(|| {
            f += 1;
            pool.install(|| {
                crowd
                    .frame(1.0 / 60.0, |i| CrowdPose {
                        transform: at(f, i),
                        locals: &rest,
                    })
                    .unwrap()
            });
            black_box(crowd.point(0, 1));
        })
    });
    let mut sims: Vec<CharacterSim> = (0..N)
        .map(|_| CharacterSim::new(sk.clone(), &settings).unwrap())
        .collect();
    g.bench_function("single_character_path", |b| {
        b.iter(|| {
            f += 1;
            for (i, sim) in sims.iter_mut().enumerate() {
                black_box(sim.frame(black_box(&rest), at(f, i), 1.0 / 60.0).unwrap());
            }
        })
    });
    g.finish();
}

criterion_group!(benches, vrm_crowd, chain_crowd);
criterion_main!(benches);
