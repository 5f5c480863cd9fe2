//! The plugin against `CharacterSim` on the same input, frame rates, despawning and bad
//! input, headless (MinimalPlugins: no window, no GPU).

mod common;

use bevy::prelude::*;
use common::*;
use std::sync::Arc;
use tassel::builtin;
use tassel::dynamics::SimMode;
use tassel::CharacterSim;
use tassel_bevy::prelude::*;

/// The built-in character (chains, springs, bone cloth, ropes) hand-spawned, animated by
/// its walk clip in `AnimationSystems` and moved in `Update`.
struct Scene {
    app: App,
    character: Entity,
    bones: Vec<Entity>,
    skeleton: tassel::Skeleton,
}

fn builtin_scene(hz: f64, mode: SimMode) -> Scene {
    builtin_scene_with(hz, mode, true)
}

/// `animate: false` keeps the bones at rest (only the character moves).
fn builtin_scene_with(hz: f64, mode: SimMode, animate: bool) -> Scene {
    let c = builtin::character();
    let mut app = app(hz);
    let (model, rig) = builtin_assets(&mut app, &c);
    let character = app
        .world_mut()
        .spawn((
            bevy_transform(&path(0.0)),
            SecondaryMotion::new(model).with_rig(rig).with_mode(mode),
        ))
        .id();
    let bones = spawn_skeleton(app.world_mut(), &c.skeleton, character);
    add_test_motion(
        &mut app,
        TestMotion {
            skeleton: c.skeleton.clone(),
            clip: c.clips[builtin::clip::WALK].clone(),
            character,
            animate,
        },
    );
    Scene {
        app,
        character,
        bones,
        skeleton: c.skeleton,
    }
}

/// The built-in character's skeleton and rig added as assets.
fn builtin_assets(
    app: &mut App,
    c: &builtin::Character,
) -> (Handle<TasselModel>, Handle<TasselRig>) {
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(c.skeleton.clone(), None));
    let rig = app
        .world_mut()
        .resource_mut::<Assets<TasselRig>>()
        .add(TasselRig(c.rig.clone()));
    (model, rig)
}

/// The reference: a `CharacterSim` of the built-in character in `mode`, compiled here as
/// the CLI does.
fn reference(mode: SimMode) -> CharacterSim {
    let c = builtin::character();
    let mut rig = c.rig.clone();
    let (_, options) = SimMode::apply(Some(mode), &mut rig, false).unwrap();
    CharacterSim::with_vrm(c.skeleton, &rig, &Default::default(), options).unwrap()
}

#[test]
fn bones_match_character_sim_bit_for_bit() {
    // Animated by a clip, and not animated at all: a bone no clip drives still holds what
    // the plugin wrote; its input must stay the animated (rest) pose, not last frame's
    // simulated one.
    for (mode, animate) in [
        (SimMode::Fixed, true),
        (SimMode::Classic, true),
        (SimMode::Fixed, false),
    ] {
        let mut scene = builtin_scene_with(60.0, mode, animate);
        let mut sim = reference(mode);
        let clip = builtin::character().clips[builtin::clip::WALK].clone();
        let simulated = sim.simulated_joints().to_vec();
        assert!(
            simulated.len() > 20,
            "the built-in rig simulates many bones"
        );
        let mut moved = 0.0f32;
        for frame in 0..240 {
            scene.app.update();
            let time = scene.app.world().resource::<Time>();
            let (t, dt) = (time.elapsed_secs(), time.delta_secs());
            // The plugin's first frame takes dt = 0, as every Tassel caller does.
            let dt = if frame == 0 { 0.0 } else { dt };
            let locals = if animate {
                animated(&scene.skeleton, &clip, t)
            } else {
                scene.skeleton.rest().to_vec()
            };
            sim.frame(&locals, path(time.elapsed_secs_f64()), dt)
                .unwrap();
            let pose = sim.pose();
            let world = scene.app.world();
            assert!(
                world.get::<TasselCharacter>(scene.character).is_some(),
                "bound on the first frame"
            );
            for &j in &simulated {
                let got = world.get::<Transform>(scene.bones[j]).unwrap();
                let want = pose.locals[j];
                assert_eq!(
                    (got.translation, got.rotation, got.scale),
                    (want.translation, want.rotation, want.scale),
                    "{mode:?} (animated: {animate}) frame {frame}: bone '{}'",
                    scene.skeleton.name(j)
                );
                moved = moved.max(got.rotation.angle_between(locals[j].rotation));
            }
        }
        // Not a pass-through: the solvers turned bones away from the animation.
        assert!(moved > 0.05, "{mode:?}: simulated bones moved {moved} rad");
    }
}

#[test]
fn this_frames_animation_and_transform_are_used() {
    // The plugin runs after `AnimationSystems` and before propagation: the bones' global
    // transforms after the update are this frame's simulated pose placed at this frame's
    // character transform (a frame late would differ by the sway of one frame).
    let mut scene = builtin_scene(60.0, SimMode::Fixed);
    for _ in 0..30 {
        scene.app.update();
    }
    let world = scene.app.world();
    let character = world.get::<TasselCharacter>(scene.character).unwrap();
    let sim = character.sim().unwrap();
    let t = world.resource::<Time>().elapsed_secs_f64();
    assert_eq!(sim.component(), path(t), "this frame's character transform");
    for &j in sim.simulated_joints() {
        let global = world.get::<GlobalTransform>(scene.bones[j]).unwrap();
        let want = sim.bone_world(j).unwrap();
        let d = global.translation().distance(want.translation);
        assert!(
            d < 1e-5,
            "bone '{}': propagated {} vs simulated {} ({d} m)",
            sim.skeleton().name(j),
            global.translation(),
            want.translation
        );
    }
}

#[test]
fn fixed_mode_agrees_at_30_60_and_144_hz() {
    // The criterion of the core's frame-rate test (crates/tassel/tests/frame_rate.rs, the
    // same sway and turn, bones at rest): at the instants the runs share (every 1/6 s over
    // 4 s), the RMS difference of the simulated bones' world positions against
    // the 144 Hz run, relative to the RMS of their dynamic deviation from the animated
    // pose at 144 Hz, is at most 1 %.
    let seconds = 4.0;
    let record = |hz: f64| {
        let mut scene = builtin_scene_with(hz, SimMode::Fixed, false);
        let frames = (seconds * hz).round() as usize;
        let per_sample = (hz / 6.0).round() as usize;
        let mut samples = Vec::new();
        for frame in 0..=frames {
            scene.app.update();
            // Bevy's first update has a delta of 0: update k is at k/hz seconds.
            if frame > 0 && frame % per_sample == 0 {
                let world = scene.app.world();
                let t = world.resource::<Time>().elapsed_secs_f64();
                assert!(
                    (t - frame as f64 / hz).abs() < 1e-6,
                    "{hz} Hz frame {frame} at {t} s"
                );
                let sim = world
                    .get::<TasselCharacter>(scene.character)
                    .unwrap()
                    .sim()
                    .unwrap();
                let anim = sim.animated_models();
                let comp = sim.component();
                let mut points = Vec::new();
                for &j in sim.simulated_joints() {
                    let p = sim.bone_world(j).unwrap().translation;
                    let a = comp.transform_point(anim[j].translation);
                    points.push((p, a));
                }
                samples.push(points);
            }
        }
        samples
    };
    let fine = record(144.0);
    let mut deviation = 0.0f64;
    let mut n = 0usize;
    for s in &fine {
        for (p, a) in s {
            deviation += p.distance_squared(*a) as f64;
            n += 1;
        }
    }
    let deviation = (deviation / n as f64).sqrt();
    assert!(
        deviation > 0.01,
        "the motion swings the bones ({deviation} m)"
    );
    for hz in [30.0, 60.0] {
        let coarse = record(hz);
        assert_eq!(coarse.len(), fine.len());
        let mut diff = 0.0f64;
        for (c, f) in coarse.iter().zip(&fine) {
            for ((p, _), (q, _)) in c.iter().zip(f) {
                diff += p.distance_squared(*q) as f64;
            }
        }
        let rel = (diff / n as f64).sqrt() / deviation;
        println!(
            "{hz} Hz vs 144 Hz: {:.3} % of the dynamic deviation",
            100.0 * rel
        );
        assert!(rel <= 0.01, "{hz} Hz differs by {:.2} %", 100.0 * rel);
    }
}

#[test]
fn despawned_characters_leave_no_state() {
    let mut scene = builtin_scene(60.0, SimMode::Fixed);
    // A second character of the same kind shares the compiled rig.
    let (model, rig) = {
        let m = scene
            .app
            .world()
            .get::<SecondaryMotion>(scene.character)
            .unwrap();
        (m.model.clone(), m.rig.clone().unwrap())
    };
    let second = scene
        .app
        .world_mut()
        .spawn((
            Transform::default(),
            SecondaryMotion::new(model).with_rig(rig),
        ))
        .id();
    spawn_skeleton(scene.app.world_mut(), &scene.skeleton, second);
    scene.app.update();
    scene.app.update();
    let world = scene.app.world();
    let a = world.get::<TasselCharacter>(scene.character).unwrap();
    let b = world.get::<TasselCharacter>(second).unwrap();
    assert!(Arc::ptr_eq(a.rig(), b.rig()), "one compiled rig");
    assert!(Arc::ptr_eq(a.rig(), a.sim().unwrap().rig()));
    // Each character holds it twice: its component and its own sim (the built-in
    // character's kind has cloths, springs and ropes: no crowd).
    assert_eq!(Arc::strong_count(a.rig()), 4);
    assert_eq!(tassel_bevy::live_character_kinds(world), 1);
    scene.app.world_mut().entity_mut(scene.character).despawn();
    scene.app.world_mut().entity_mut(second).despawn();
    scene.app.update();
    let world = scene.app.world_mut();
    assert_eq!(
        tassel_bevy::live_character_kinds(world),
        0,
        "the compiled rig is freed"
    );
    assert_eq!(world.query::<&TasselCharacter>().iter(world).count(), 0);
    assert_eq!(
        world.query::<&Bone>().iter(world).count(),
        0,
        "the bones went too"
    );
}

#[test]
fn changing_the_mode_restarts_the_character() {
    let mut scene = builtin_scene(60.0, SimMode::Fixed);
    scene.app.update();
    let before = scene
        .app
        .world()
        .get::<TasselCharacter>(scene.character)
        .unwrap()
        .sim()
        .unwrap()
        .rig()
        .clone();
    scene
        .app
        .world_mut()
        .get_mut::<SecondaryMotion>(scene.character)
        .unwrap()
        .mode = SimMode::Classic;
    scene.app.update();
    let world = scene.app.world();
    let after = world
        .get::<TasselCharacter>(scene.character)
        .unwrap()
        .sim()
        .unwrap()
        .rig();
    assert!(!Arc::ptr_eq(&before, after), "a new compiled rig");
    assert_eq!(
        after.chains().chain_settings(0).mode,
        tassel::dynamics::chain::TimeMode::Classic
    );
}

#[test]
fn a_nan_bone_skips_the_frame_and_the_next_good_frame_carries_on() {
    let mut scene = builtin_scene(60.0, SimMode::Fixed);
    for _ in 0..10 {
        scene.app.update();
    }
    // A system that poisons one animated bone for one frame, after the animation.
    #[derive(Resource)]
    struct Poison(Entity, bool);
    fn poison(mut p: ResMut<Poison>, mut q: Query<&mut Transform>) {
        if p.1 {
            q.get_mut(p.0).unwrap().rotation = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
            p.1 = false;
        }
    }
    let target = scene.bones[scene.skeleton.find("spine").unwrap_or(1)];
    scene.app.insert_resource(Poison(target, true)).add_systems(
        PostUpdate,
        poison
            .after(bevy::app::AnimationSystems)
            .before(TasselSystems::Step),
    );
    scene.app.update();
    {
        let world = scene.app.world();
        let errors = &world.resource::<Errors>().0;
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(
            errors[0].message.contains("not finite"),
            "{}",
            errors[0].message
        );
        let c = world.get::<TasselCharacter>(scene.character).unwrap();
        assert!(c.error().is_some());
    }
    for _ in 0..30 {
        scene.app.update();
    }
    let world = scene.app.world();
    let c = world.get::<TasselCharacter>(scene.character).unwrap();
    assert!(c.error().is_none(), "recovered");
    for &e in &scene.bones {
        let t = world.get::<Transform>(e).unwrap();
        assert!(
            t.translation.is_finite() && t.rotation.is_finite(),
            "no NaN written"
        );
    }
}

#[test]
fn a_missing_bone_is_an_error_naming_it() {
    let c = builtin::character();
    let mut app = app(60.0);
    let (model, rig) = builtin_assets(&mut app, &c);
    let character = app
        .world_mut()
        .spawn((
            Transform::default(),
            SecondaryMotion::new(model).with_rig(rig),
        ))
        .id();
    let bones = spawn_skeleton(app.world_mut(), &c.skeleton, character);
    // Rename one simulated bone's entity.
    let sim = reference(SimMode::Fixed);
    let victim = sim.simulated_joints()[3];
    app.world_mut()
        .entity_mut(bones[victim])
        .insert(Name::new("renamed"));
    app.update();
    let world = app.world();
    let failed = world.get::<TasselFailed>(character).expect("TasselFailed");
    let name = c.skeleton.name(victim);
    assert!(failed.0.contains(&format!("'{name}'")), "{}", failed.0);
    assert!(world.get::<TasselCharacter>(character).is_none());
    assert_eq!(world.resource::<Errors>().0.len(), 1);
}

#[test]
fn bad_rig_files_are_errors_not_panics() {
    let dir = std::env::temp_dir().join(format!("tassel-bevy-rigs-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("broken.rig.toml"), "[[chains]\nname = ").unwrap();
    std::fs::write(
        dir.join("nobone.rig.toml"),
        "[[chain]]\nname = \"tail\"\nroot = \"no_such_bone\"\n",
    )
    .unwrap();
    for (file, expect) in [
        ("broken.rig.toml", "broken.rig.toml"),
        ("nobone.rig.toml", "no_such_bone"),
    ] {
        let c = builtin::character();
        let mut app = app_with_assets(60.0, dir.to_str().unwrap());
        let model = app
            .world_mut()
            .resource_mut::<Assets<TasselModel>>()
            .add(TasselModel::new(c.skeleton.clone(), None));
        let rig: Handle<TasselRig> = app.world().resource::<AssetServer>().load(file);
        let character = app
            .world_mut()
            .spawn((
                Transform::default(),
                SecondaryMotion::new(model).with_rig(rig),
            ))
            .id();
        spawn_skeleton(app.world_mut(), &c.skeleton, character);
        let failed = update_until(&mut app, 2000, |app| {
            app.world().get::<TasselFailed>(character).is_some()
        });
        assert!(failed, "{file}: no TasselFailed");
        let world = app.world();
        let message = &world.get::<TasselFailed>(character).unwrap().0;
        assert!(message.contains(expect), "{file}: {message}");
        let errors = &world.resource::<Errors>().0;
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert_eq!(errors[0].entity, character);
    }
    std::fs::remove_dir_all(&dir).ok();
}
