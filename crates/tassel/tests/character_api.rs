//! The character API: one compiled rig shared by many characters, results by name and in
//! world space without allocation.

use glam::{Quat, Vec3};
use std::sync::Arc;
use tassel::dynamics::vrm::{VrmMode, VrmOptions};
use tassel::{builtin, CharacterRig, CharacterSim, Transform};

fn walk(t: f32) -> Transform {
    Transform::from_translation_rotation(
        Vec3::new(0.4 * (3.0 * t).sin(), 0.0, 0.7 * t),
        Quat::from_rotation_y(0.6 * (2.0 * t).sin()),
    )
}

#[test]
fn a_shared_rig_gives_each_character_the_bits_of_its_own_compile() {
    let c = builtin::character();
    let shared = Arc::new(CharacterRig::new(c.skeleton.clone(), &c.rig).unwrap());
    let mut a = CharacterSim::from_rig(shared.clone());
    let mut b = CharacterSim::from_rig(shared.clone());
    let mut own = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    assert_eq!(Arc::strong_count(&shared), 3);
    let clip = &c.clips[builtin::clip::RUN];
    let mut locals = c.skeleton.rest().to_vec();
    for k in 0..300 {
        let t = k as f32 / 60.0;
        locals.copy_from_slice(c.skeleton.rest());
        clip.sample_looped(t, &mut locals);
        let dt = if k == 0 { 0.0 } else { 1.0 / 60.0 };
        let pa = a.frame(&locals, walk(t), dt).unwrap().clone();
        // b runs half a second behind on another path: its state is its own.
        b.frame(&locals, walk(t - 0.5), dt).unwrap();
        let po = own.frame(&locals, walk(t), dt).unwrap();
        assert_eq!(pa.locals, po.locals, "frame {k}");
        assert_eq!(pa.models, po.models, "frame {k}");
    }
    assert_ne!(a.pose().models, b.pose().models);
}

#[test]
fn simulated_joints_are_each_solvers_bones_once_ascending() {
    let c = builtin::character();
    let sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let joints = sim.simulated_joints();
    assert!(
        joints.windows(2).all(|w| w[0] < w[1]),
        "ascending, no repeats"
    );
    // Independently from each solver's own list.
    let mut want: Vec<usize> = Vec::new();
    want.extend(sim.chains().rotating_joints().map(|(j, _, _)| j));
    want.extend((0..sim.chains().point_count()).filter_map(|p| {
        let info = sim.chains().point(p);
        info.parent.and(info.joint)
    }));
    want.extend((0..sim.springs().len()).map(|i| sim.springs().joint(i)));
    want.extend(sim.cloths().simulated_joints());
    want.extend(sim.ropes().simulated_joints());
    // The pinned first bones a cloth or a rope turns toward its first free point.
    let sk = sim.skeleton();
    for j in sim
        .cloths()
        .simulated_joints()
        .chain(sim.ropes().simulated_joints())
    {
        if let Some(p) = sk.parent(j) {
            want.push(p);
        }
    }
    want.sort_unstable();
    want.dedup();
    assert_eq!(joints, &want[..]);
    // The same slice each call: no allocation per call.
    assert_eq!(joints.as_ptr(), sim.simulated_joints().as_ptr());
}

#[test]
fn world_space_results_by_name() {
    let c = builtin::character();
    let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let mut locals = c.skeleton.rest().to_vec();
    let comp = walk(1.3);
    for k in 0..90 {
        locals.copy_from_slice(c.skeleton.rest());
        c.clips[builtin::clip::WALK].sample_looped(k as f32 / 60.0, &mut locals);
        sim.frame(&locals, comp, if k == 0 { 0.0 } else { 1.0 / 60.0 })
            .unwrap();
    }
    assert_eq!(sim.component(), comp);
    // A bone's world transform is the character's transform times its model transform,
    // computed here from the output locals by walking the parents.
    let name = c.skeleton.name(c.skeleton.len() - 1).to_string();
    let j = sim.bone(&name).unwrap();
    let mut model = sim.pose().locals[j];
    let mut p = c.skeleton.parent(j);
    while let Some(i) = p {
        model = sim.pose().locals[i] * model;
        p = c.skeleton.parent(i);
    }
    let world = sim.bone_world_by_name(&name).unwrap();
    assert!(
        world
            .translation
            .distance(comp.transform_point(model.translation))
            < 1e-5
    );
    assert!(sim.bone_world(c.skeleton.len()).is_none());
    assert!(sim.bone_world_by_name("no such bone").is_none());
    // A chain's tip: the chain state's last point, placed by the character transform.
    let rig = sim.rig().clone();
    for i in 0..rig.chains().chain_count() {
        let name = rig.chains().chain_settings(i).name.clone();
        assert_eq!(rig.chain_index(&name), Some(i));
        let last = rig.chains().chain_points(i).end - 1;
        let want = comp.transform_point(sim.chain_state().output_positions()[last]);
        assert_eq!(sim.chain_tip_world(&name), Some(want), "chain {name}");
    }
    assert!(sim.chain_tip_world("no such chain").is_none());
}

#[test]
fn vrm_tails_in_world_space_without_allocation() {
    let (skeleton, springs) = builtin::bench_vrm(4, 5, 2);
    for mode in [VrmMode::Spec, VrmMode::Fixed] {
        let options = VrmOptions {
            mode,
            ..VrmOptions::default()
        };
        let mut sim =
            CharacterSim::with_vrm(skeleton.clone(), &Default::default(), &springs, options)
                .unwrap();
        let rest = skeleton.rest().to_vec();
        for k in 0..60 {
            sim.frame(
                &rest,
                walk(k as f32 / 60.0),
                if k == 0 { 0.0 } else { 1.0 / 60.0 },
            )
            .unwrap();
        }
        let all = sim
            .vrm_state()
            .tails_world(sim.vrm(), &sim.component(), &sim.pose().models);
        for (i, link) in sim.vrm().links.iter().enumerate() {
            assert_eq!(sim.vrm_tail_world(link.joint), Some(all[i]));
        }
        assert_eq!(sim.vrm_tail_world(0), None, "the root is not a spring");
    }
}

#[test]
fn output_models_are_the_output_locals_composed() {
    // An engine writes the locals back and composes them itself: the model pose the
    // character reports must be what those locals give.
    let c = builtin::character();
    let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let mut locals = c.skeleton.rest().to_vec();
    let mut worst = (0.0f32, 0usize, 0usize);
    for k in 0..240 {
        let t = k as f32 / 60.0;
        locals.copy_from_slice(c.skeleton.rest());
        c.clips[builtin::clip::WALK].sample_looped(t, &mut locals);
        sim.frame(&locals, walk(t), if k == 0 { 0.0 } else { 1.0 / 60.0 })
            .unwrap();
        let pose = sim.pose();
        let mut models = pose.locals.clone();
        for j in 0..models.len() {
            if let Some(p) = c.skeleton.parent(j) {
                models[j] = models[p] * pose.locals[j];
            }
        }
        for j in 0..models.len() {
            let d = models[j].translation.distance(pose.models[j].translation);
            if d > worst.0 {
                worst = (d, j, k);
            }
        }
    }
    assert!(
        worst.0 < 1e-5,
        "joint '{}' frame {}: {} m",
        c.skeleton.name(worst.1),
        worst.2,
        worst.0
    );
}

#[test]
fn only_the_simulated_joints_change() {
    // What an engine copies back (`simulated_joints`) is every joint whose local the
    // solvers changed.
    let c = builtin::character();
    let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    let mut locals = c.skeleton.rest().to_vec();
    let mut changed = vec![false; c.skeleton.len()];
    for k in 0..240 {
        let t = k as f32 / 60.0;
        locals.copy_from_slice(c.skeleton.rest());
        c.clips[builtin::clip::WALK].sample_looped(t, &mut locals);
        sim.frame(&locals, walk(t), if k == 0 { 0.0 } else { 1.0 / 60.0 })
            .unwrap();
        for (j, l) in sim.pose().locals.iter().enumerate() {
            changed[j] |= *l != locals[j];
        }
    }
    let changed: Vec<&str> = (0..changed.len())
        .filter(|&j| changed[j] && !sim.simulated_joints().contains(&j))
        .map(|j| c.skeleton.name(j))
        .collect();
    assert!(changed.is_empty(), "changed but not listed: {changed:?}");
}

#[test]
fn reset_is_a_fresh_start() {
    // After reset(), the next frames equal those of a new character given the same input:
    // nothing of the old motion leaks through (VRM springs in every mode, and every solver
    // of the built-in character).
    let (skeleton, springs) = builtin::bench_vrm(4, 5, 2);
    let c = builtin::character();
    let mut cases: Vec<(String, CharacterSim)> = [VrmMode::Spec, VrmMode::ThreeVrm, VrmMode::Fixed]
        .into_iter()
        .map(|mode| {
            let options = VrmOptions {
                mode,
                ..VrmOptions::default()
            };
            let sim =
                CharacterSim::with_vrm(skeleton.clone(), &Default::default(), &springs, options)
                    .unwrap();
            (format!("VRM {mode:?}"), sim)
        })
        .collect();
    cases.push((
        "built-in".into(),
        CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap(),
    ));
    for (name, mut used) in cases {
        let mut fresh = used.clone();
        let rest = used.skeleton().rest().to_vec();
        for k in 0..37 {
            used.frame(
                &rest,
                walk(k as f32 / 50.0),
                if k == 0 { 0.0 } else { 1.0 / 50.0 },
            )
            .unwrap();
        }
        used.reset();
        for k in 0..120 {
            let t = 3.0 + k as f32 / 60.0;
            let dt = if k == 0 { 0.0 } else { 1.0 / 60.0 };
            let a = used.frame(&rest, walk(t), dt).unwrap().clone();
            let b = fresh.frame(&rest, walk(t), dt).unwrap();
            assert_eq!(a.locals, b.locals, "{name}: frame {k} after the reset");
        }
    }
}
