//! Real files through Bevy's own glTF loader, headless: the scene spawned the Bevy way
//! (`WorldAssetRoot`), bones found by the names Bevy gives glTF nodes, the file's VRM
//! springs read by the plugin from the same path; the bones move as `CharacterSim` moves
//! them on the same input.

mod common;

use bevy::animation::AnimationPlugin;
use bevy::asset::RenderAssetUsages;
use bevy::gltf::{GltfLoaderSettings, GltfPlugin};
use bevy::image::ImagePlugin;
use bevy::mesh::MeshPlugin;
use bevy::prelude::*;
use bevy::world_serialization::{WorldAsset, WorldAssetRoot, WorldSerializationPlugin};
use common::*;
use tassel::dynamics::SimMode;
use tassel::CharacterSim;
use tassel_bevy::prelude::*;

/// A headless app that can load glTF scenes (no meshes, materials, lights or cameras are
/// kept: there is no renderer).
fn gltf_app(folder: &str) -> App {
    let mut app = app_with_assets(60.0, folder);
    app.add_plugins((
        ImagePlugin::default(),
        MeshPlugin,
        AnimationPlugin,
        WorldSerializationPlugin,
        GltfPlugin::default(),
    ));
    // What the glTF scene's entities carry, registered for the scene spawner (the
    // renderer's plugins would do it).
    app.register_type::<Visibility>()
        .register_type::<InheritedVisibility>()
        .register_type::<ViewVisibility>()
        .register_type::<Name>()
        .register_type::<Transform>()
        .register_type::<GlobalTransform>()
        .register_type::<bevy::gltf::GltfExtras>()
        .register_type::<bevy::gltf::GltfSceneExtras>()
        .register_type::<ChildOf>()
        .register_type::<Children>()
        .register_type::<bevy::transform::components::TransformTreeChanged>()
        .register_type::<bevy::animation::AnimationTargetId>()
        .register_type::<bevy::animation::AnimatedBy>();
    // The `.vrm` scene loader is registered when the app finishes building.
    app.finish();
    app.cleanup();
    app
}

fn spawn_scene(app: &mut App, file: &str, mode: SimMode) -> Entity {
    spawn_scene_with(app, file, mode, None, true)
}

/// A scene of `file` with its VRM springs (or the rig file `rig`), in its kind's crowd or
/// on its own sim.
fn spawn_scene_with(
    app: &mut App,
    file: &str,
    mode: SimMode,
    rig: Option<&Handle<TasselRig>>,
    crowd: bool,
) -> Entity {
    let (scene, model) = load_scene(app, file);
    let mut motion = SecondaryMotion::new(model).with_mode(mode);
    if let Some(rig) = rig {
        motion = motion.with_rig(rig.clone());
    }
    if !crowd {
        motion = motion.without_crowd();
    }
    app.world_mut()
        .spawn((WorldAssetRoot(scene), motion, Transform::default()))
        .id()
}

/// The handles of `file`'s first scene (without meshes, materials, cameras, lights or
/// animations) and of its model, as [`spawn_scene_with`] loads them.
fn load_scene(app: &mut App, file: &str) -> (Handle<WorldAsset>, Handle<TasselModel>) {
    let server = app.world().resource::<AssetServer>().clone();
    let scene: Handle<WorldAsset> = server
        .load_builder()
        .with_settings(|s: &mut GltfLoaderSettings| {
            s.load_meshes = RenderAssetUsages::empty();
            s.load_materials = RenderAssetUsages::empty();
            s.load_cameras = false;
            s.load_lights = false;
            s.load_animations = false;
        })
        .load(GltfAssetLabel::Scene(0).from_asset(file.to_string()));
    let model = server.load::<TasselModel>(file.to_string());
    (scene, model)
}

#[derive(Component)]
struct Mover;

/// Each named entity's `Transform` when first seen, before the plugin writes any: Bevy's
/// reading of the file's nodes.
#[derive(Resource, Default)]
struct FirstSeen(bevy::platform::collections::HashMap<Entity, Transform>);

fn record_first_seen(mut seen: ResMut<FirstSeen>, q: Query<(Entity, &Transform), With<Name>>) {
    for (e, t) in &q {
        seen.0.entry(e).or_insert(*t);
    }
}

fn move_it(time: Res<Time>, mut q: Query<&mut Transform, With<Mover>>) {
    for mut t in &mut q {
        *t = bevy_transform(&path(time.elapsed_secs_f64()));
    }
}

#[test]
fn vrm_files_spawned_by_bevy_move_as_character_sim_moves_them() {
    let Some(root) = testdata() else { return };
    // Every VRM fixture: 0.x-free VRM 1.0 GLBs and a .gltf whose buffer is a separate
    // .bin (read through the asset source).
    let mut files: Vec<String> = std::fs::read_dir(root.join("vrm"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".vrm") || n.ends_with(".gltf"))
        .map(|n| format!("vrm/{n}"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "the VRM fixtures: {files:?}");
    let mut tested = 0;
    for file in &files {
        let file = file.as_str();
        for mode in [SimMode::Fixed, SimMode::Spec] {
            let mut app = gltf_app(root.to_str().unwrap());
            app.add_systems(Update, move_it)
                .init_resource::<FirstSeen>()
                .add_systems(PostUpdate, record_first_seen.before(TasselSystems::Bind));
            let character = spawn_scene(&mut app, file, mode);
            app.world_mut().entity_mut(character).insert(Mover);
            let ready = update_until(&mut app, 3000, |app| {
                let w = app.world();
                if let Some(f) = w.get::<TasselFailed>(character) {
                    panic!("{file}: {}", f.0);
                }
                w.get::<TasselCharacter>(character).is_some()
            });
            if !ready {
                let w = app.world();
                let server = w.resource::<AssetServer>();
                let m = &w.get::<SecondaryMotion>(character).unwrap().model;
                let scene = &w.get::<WorldAssetRoot>(character).unwrap().0;
                panic!(
                    "{file}: the character never started; model {:?}, scene {:?}, children {:?}",
                    server.load_state(m),
                    server.load_state(scene),
                    w.get::<Children>(character).map(|c| c.len())
                );
            }
            // The reference: the same file through tassel_gltf, the same mode.
            let model = tassel_gltf::load(&root.join(file)).unwrap();
            let springs = model.vrm.as_ref().expect("a VRM file").springs.clone();
            let mut rig = Default::default();
            let (_, options) = SimMode::apply(Some(mode), &mut rig, true).unwrap();
            let mut sim =
                CharacterSim::with_vrm(model.skeleton.clone(), &rig, &springs, options).unwrap();
            let (bones, space, joints) = {
                let c = app.world().get::<TasselCharacter>(character).unwrap();
                // VRM-only kinds step in a crowd: no sim of their own.
                assert!(c.in_crowd() && c.sim().is_none(), "{file}: in a crowd");
                let sk = c.skeleton();
                let bones: Vec<Entity> = (0..sk.len())
                    .map(|j| c.bone_entity(sk.name(j)).expect("every node has an entity"))
                    .collect();
                (bones, c.space(), c.simulated_joints().to_vec())
            };
            assert!(!joints.is_empty());
            // Both start from the pose on the next frame (the plugin has run since binding).
            app.world_mut()
                .get_mut::<TasselCharacter>(character)
                .unwrap()
                .reset();
            let mut first = true;
            let mut swing = 0.0f32;
            for frame in 0..180 {
                app.update();
                let world = app.world();
                let time = world.resource::<Time>();
                // The input the plugin saw: the scene's node transforms (Bevy's reading of
                // the file) and the scene entity placed on the character's path.
                let locals: Vec<tassel::Transform> = bones
                    .iter()
                    .enumerate()
                    .map(|(j, &e)| {
                        if joints.contains(&j) {
                            let t = world.resource::<FirstSeen>().0[&e];
                            tassel::Transform::new(t.translation, t.rotation, t.scale)
                        } else {
                            let t = world.get::<Transform>(e).unwrap();
                            tassel::Transform::new(t.translation, t.rotation, t.scale)
                        }
                    })
                    .collect();
                let mut component = path(time.elapsed_secs_f64());
                let mut at = space;
                let mut parents = vec![];
                while let Some(e) = at {
                    if e == character {
                        break;
                    }
                    parents.push(e);
                    at = world.get::<ChildOf>(e).map(ChildOf::parent);
                }
                for e in parents.into_iter().rev() {
                    let t = world.get::<Transform>(e).unwrap();
                    component =
                        component * tassel::Transform::new(t.translation, t.rotation, t.scale);
                }
                let dt = if first { 0.0 } else { time.delta_secs() };
                first = false;
                sim.frame(&locals, component, dt).unwrap();
                let pose = sim.pose();
                for &j in &joints {
                    let got = world.get::<Transform>(bones[j]).unwrap();
                    let want = pose.locals[j];
                    // Quaternion components, not `angle_between` (its acos is off by 1e-3
                    // rad for quaternions a rounding apart).
                    let dq = (got.rotation - want.rotation)
                        .length()
                        .min((got.rotation + want.rotation).length());
                    let d = got.translation.distance(want.translation) + dq;
                    assert!(
                        d < 1e-6,
                        "{file} {mode:?} frame {frame}: joint '{}' differs by {d}",
                        model.skeleton.name(j)
                    );
                    swing = swing.max(
                        want.rotation
                            .angle_between(model.skeleton.rest()[j].rotation),
                    );
                }
            }
            assert!(
                swing > 0.01,
                "{file} {mode:?}: the springs swing ({swing} rad)"
            );
            tested += 1;
        }
    }
    assert_eq!(tested, 2 * files.len());
}

/// Moves its entity on the test path, `phase` seconds ahead.
#[derive(Component, Clone, Copy)]
struct Phase(f64);

fn move_by_phase(time: Res<Time>, mut q: Query<(&mut Transform, &Phase)>) {
    for (mut t, phase) in &mut q {
        *t = bevy_transform(&path(time.elapsed_secs_f64() + phase.0));
    }
}

/// The bits of a `Transform`.
fn bits(t: &Transform) -> [u32; 10] {
    let mut b = [0u32; 10];
    let values = t
        .translation
        .to_array()
        .into_iter()
        .chain(t.rotation.to_array())
        .chain(t.scale.to_array());
    for (k, v) in values.enumerate() {
        b[k] = v.to_bits();
    }
    b
}

/// Characters of one kind in its crowd give the bones, bit for bit, that the same
/// characters on their own `CharacterSim`s give (each crowd character has a twin without
/// the crowd, on the same path): every VRM file (a `VrmCrowd`) and Fox.glb with a chain
/// rig (a `ChainCrowd`), characters joining on different frames and one leaving mid-run.
#[test]
fn crowd_characters_move_as_their_own_sims_move_them() {
    let Some(root) = testdata() else { return };
    let mut cases: Vec<(String, Option<tassel::dynamics::RigSettings>)> =
        std::fs::read_dir(root.join("vrm"))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".vrm") || n.ends_with(".gltf"))
            .map(|n| (format!("vrm/{n}"), None))
            .collect();
    cases.sort_by(|a, b| a.0.cmp(&b.0));
    // The fox's tail as a bone chain (the rig file of the repository, added as an asset).
    let fox = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/fox.toml");
    let fox = tassel::dynamics::RigSettings::from_toml_str(&std::fs::read_to_string(fox).unwrap())
        .unwrap();
    cases.push(("gltf/Fox.glb".into(), Some(fox)));
    let mut crowds_seen = 0;
    for (file, rig) in &cases {
        let mut app = gltf_app(root.to_str().unwrap());
        app.add_systems(Update, move_by_phase);
        let rig = rig.clone().map(|r| {
            app.world_mut()
                .resource_mut::<Assets<TasselRig>>()
                .add(TasselRig(r))
        });
        // The file loaded before the first frame counted, so that the pairs start on the
        // frames they are spawned (loading runs on other threads: on a busy machine it took
        // most of the 150 frames, and too few bones were compared).
        let held = load_scene(&mut app, file);
        let loaded = update_until(&mut app, 5000, |app| {
            let server = app.world().resource::<AssetServer>();
            server.is_loaded_with_dependencies(&held.0)
                && server.is_loaded_with_dependencies(&held.1)
        });
        assert!(loaded, "{file}: the scene and the model load");
        // Pairs (crowd, own sim), spawned on frames 0, 5 and 12; pair 1 leaves on frame 60.
        let mut pairs: Vec<(Entity, Entity)> = Vec::new();
        let mut compared = 0usize;
        let mut swing = 0.0f32;
        for frame in 0..150 {
            if [0, 5, 12].contains(&frame) {
                let phase = Phase(0.37 * pairs.len() as f64);
                let a = spawn_scene_with(&mut app, file, SimMode::Fixed, rig.as_ref(), true);
                let b = spawn_scene_with(&mut app, file, SimMode::Fixed, rig.as_ref(), false);
                app.world_mut().entity_mut(a).insert(phase);
                app.world_mut().entity_mut(b).insert(phase);
                pairs.push((a, b));
            }
            if frame == 60 {
                let (a, b) = pairs.remove(1);
                app.world_mut().entity_mut(a).despawn();
                app.world_mut().entity_mut(b).despawn();
            }
            app.update();
            let world = app.world();
            for &(a, b) in &pairs {
                let (Some(ca), Some(cb)) = (
                    world.get::<TasselCharacter>(a),
                    world.get::<TasselCharacter>(b),
                ) else {
                    if let Some(f) = world.get::<TasselFailed>(a) {
                        panic!("{file}: {}", f.0);
                    }
                    continue;
                };
                assert!(ca.in_crowd(), "{file}: the crowd character is in a crowd");
                assert!(!cb.in_crowd(), "{file}: its twin is not");
                assert_eq!(ca.simulated_bones().len(), cb.simulated_bones().len());
                for (&(j, ea), &(k, eb)) in ca.simulated_bones().iter().zip(cb.simulated_bones()) {
                    assert_eq!(j, k);
                    let (ta, tb) = (
                        world.get::<Transform>(ea).unwrap(),
                        world.get::<Transform>(eb).unwrap(),
                    );
                    assert_eq!(
                        bits(ta),
                        bits(tb),
                        "{file} frame {frame}: joint '{}': crowd {ta:?}, own sim {tb:?}",
                        ca.skeleton().name(j)
                    );
                    let rest = ca.skeleton().rest()[j].rotation;
                    swing = swing.max(ta.rotation.angle_between(rest));
                    compared += 1;
                }
            }
        }
        assert!(compared > 300, "{file}: {compared} bones compared");
        assert!(swing > 0.01, "{file}: the bones swing ({swing} rad)");
        crowds_seen += 1;
    }
    assert_eq!(crowds_seen, cases.len());
}

/// A scene that fails to load (here: a file that does not exist) gives `TasselFailed` with
/// the loader's message, not an endless wait, while the model loaded fine.
#[test]
fn a_scene_that_fails_to_load_is_reported() {
    let Some(root) = testdata() else { return };
    let mut app = gltf_app(root.to_str().unwrap());
    let server = app.world().resource::<AssetServer>().clone();
    let scene: Handle<WorldAsset> =
        server.load(GltfAssetLabel::Scene(0).from_asset("vrm/no_such_file.vrm"));
    let model = server.load::<TasselModel>("vrm/smoke_spring.vrm");
    let character = app
        .world_mut()
        .spawn((
            WorldAssetRoot(scene),
            SecondaryMotion::new(model),
            Transform::default(),
        ))
        .id();
    let failed = update_until(&mut app, 600, |app| {
        app.world().get::<TasselFailed>(character).is_some()
    });
    assert!(failed, "no TasselFailed after 600 frames");
    let message = &app.world().get::<TasselFailed>(character).unwrap().0;
    assert!(
        message.contains("scene") && message.contains("no_such_file"),
        "{message}"
    );
    assert!(app.world().get::<TasselCharacter>(character).is_none());
}
