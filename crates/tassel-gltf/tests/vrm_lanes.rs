//! The VRM springs' update with several springs side by side in SIMD lanes, on the real
//! VRM files in ../shared/testdata/vrm/: the bits of the scalar update (the readable
//! reference) frame after frame, in the `spec`, `three-vrm` and `fixed` (60 and 90 Hz)
//! modes, portable and with AVX2 where the CPU has it.

mod common;

use common::{bits, input, vrm_files};
use tassel::crowd::SimdUse;
use tassel::dynamics::vrm::{VrmMode, VrmOptions, VrmSpringBones};
use tassel::dynamics::RigSettings;
use tassel::{CharacterSim, Skeleton};

/// 600 frames (a hitch at frame 300) through one `CharacterSim` per way of running the
/// update: every local and model transform the same bits. Returns the largest turn of a
/// spring joint from its rest rotation.
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
    let ways = [
        SimdUse::Scalar,
        SimdUse::Portable,
        SimdUse::Avx2,
        SimdUse::Auto,
    ];
    let mut sims: Vec<CharacterSim> = ways
        .iter()
        .map(|&w| {
            let mut s = CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), bones, options)
                .unwrap();
            s.set_simd(w);
            s
        })
        .collect();
    let swing = sims[0]
        .vrm()
        .links
        .first()
        .and_then(|l| l.parent)
        .unwrap_or(0);
    let mut locals = sk.rest().to_vec();
    let mut turned = 0.0f32;
    for f in 0..600 {
        let transform = input(sk, swing, 0, f, &mut locals);
        let dt = if f == 300 { 0.2 } else { 1.0 / 60.0 };
        let reference = sims[0].frame(&locals, transform, dt).unwrap().clone();
        for (w, sim) in ways.iter().zip(&mut sims).skip(1) {
            let pose = sim.frame(&locals, transform, dt).unwrap();
            for j in 0..sk.len() {
                assert_eq!(
                    (bits(&pose.locals[j]), bits(&pose.models[j])),
                    (bits(&reference.locals[j]), bits(&reference.models[j])),
                    "{name} {mode:?} at {step_rate} Hz, {w:?}: frame {f}, joint '{}'",
                    sk.name(j)
                );
            }
        }
        for l in &sims[0].vrm().links {
            let r = reference.locals[l.joint].rotation;
            turned = turned.max(r.angle_between(l.rest_local.rotation));
        }
    }
    turned
}

#[test]
fn lanes_give_the_scalar_bits_on_every_vrm_file() {
    let mut with_lanes = 0;
    for path in vrm_files() {
        let model = tassel_gltf::load(&path).unwrap();
        let bones = model.vrm.clone().unwrap().springs;
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        let sim = CharacterSim::with_vrm(
            model.skeleton.clone(),
            &RigSettings::default(),
            &bones,
            VrmOptions::default(),
        )
        .unwrap();
        let groups = sim.vrm().lane_groups();
        eprintln!(
            "{name}: {} spring joints in {groups} lane groups",
            sim.vrm().links.len()
        );
        if groups > 0 {
            with_lanes += 1;
        }
        for mode in [
            (VrmMode::Spec, 60.0),
            (VrmMode::ThreeVrm, 60.0),
            (VrmMode::Fixed, 60.0),
            (VrmMode::Fixed, 90.0),
        ] {
            let turned = compare(&name, &model.skeleton, &bones, mode);
            assert!(
                turned > 0.05,
                "{name} {mode:?}: the springs never moved ({turned} rad)"
            );
        }
    }
    if !vrm_files().is_empty() {
        // Not a vacuous comparison: most files run in lanes.
        assert!(with_lanes >= 4, "only {with_lanes} files run in lanes");
    }
}
