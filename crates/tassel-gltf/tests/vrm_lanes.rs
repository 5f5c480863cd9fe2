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

/// The built-in avatar's springs test different colliders: the ponytail the head and torso
/// (colliders 0, 1), the locks the head (0), the charm the left thigh (2), the tail and the
/// skirt's eight columns the legs in the order thigh_l, thigh_r, shin_l, shin_r (2, 4, 3,
/// 5). Longest first, the tail's list is the group's; the ponytail's adds two entries to 7
/// rows (14 tests) where a group of its own would cost 5 x (4 + 2) = 30: taken, and every
/// other list is then inside. So its 13 columns share groups of LANES lanes, a collider
/// mask per lane. Still the scalar bits, and the colliders do act (the same run without
/// them turns the joints elsewhere).
#[test]
fn springs_with_different_colliders_share_lanes_and_keep_the_scalar_bits() {
    let model =
        tassel_gltf::load_slice(&tassel_gltf::builtin_avatar().unwrap(), None, "avatar.vrm")
            .unwrap();
    let bones = model.vrm.clone().unwrap().springs;
    let lists: std::collections::BTreeSet<Vec<usize>> = bones
        .springs
        .iter()
        .map(|s| s.collider_groups.clone())
        .collect();
    assert!(lists.len() >= 4, "{lists:?}");
    let sim = CharacterSim::with_vrm(
        model.skeleton.clone(),
        &RigSettings::default(),
        &bones,
        VrmOptions::default(),
    )
    .unwrap();
    // 13 columns, none below another spring, none with a centre.
    assert_eq!(
        sim.vrm().lane_groups(),
        13usize.div_ceil(tassel::crowd::lanes::LANES)
    );
    for mode in [
        (VrmMode::Spec, 60.0),
        (VrmMode::ThreeVrm, 60.0),
        (VrmMode::Fixed, 60.0),
        (VrmMode::Fixed, 90.0),
    ] {
        let turned = compare("avatar", &model.skeleton, &bones, mode);
        assert!(turned > 0.05, "{mode:?}: the springs never moved");
    }
    // The colliders act: without them the joints end up elsewhere.
    let mut free = bones.clone();
    for s in &mut free.springs {
        s.collider_groups.clear();
    }
    let run = |b: &VrmSpringBones| {
        let sk = &model.skeleton;
        let mut sim = CharacterSim::with_vrm(
            sk.clone(),
            &RigSettings::default(),
            b,
            VrmOptions::default(),
        )
        .unwrap();
        let swing = sim.vrm().links[0].parent.unwrap();
        let mut locals = sk.rest().to_vec();
        let mut out = Vec::new();
        for f in 0..300 {
            let t = input(sk, swing, 0, f, &mut locals);
            out = sim.frame(&locals, t, 1.0 / 60.0).unwrap().locals.clone();
        }
        out
    };
    let (with, without) = (run(&bones), run(&free));
    let moved = sim
        .vrm()
        .links
        .iter()
        .filter(|l| with[l.joint].rotation != without[l.joint].rotation)
        .count();
    assert!(moved > 10, "only {moved} joints felt the colliders");
}
