//! tassel-bevy's VRM spring bones against bevy_vrm1 0.10's spring-bone system, side by
//! side in one run: four headless Bevy 0.19 apps (`MinimalPlugins`, transforms, 1/60 s a
//! frame) with the same N avatars swaying on their roots, one with `TasselPlugin` in
//! `fixed` mode (the default), one in `spec` mode (one update a frame, the work bevy_vrm1
//! does), one with bevy_vrm1's `VrmSpringBonePlugin`, one with no secondary motion.
//!
//! The avatar is Tassel's bench avatar (`tassel::builtin::bench_vrm(2, 9, 4)`, as the
//! plugin's `crowd` example): two strands of eight spring joints (stiffness 1, gravity 1,
//! drag 0.5, hit radius 2 cm) and four colliders (spheres and capsules) on the root, spawned as a
//! hierarchy of named entities. bevy_vrm1 gets the same springs as its own components
//! (`SpringRoot` on each strand's first joint, `SpringJointProps` on each joint, a
//! `ColliderShape` per collider): its loader needs the renderer and a VRM 1.0 file, so
//! the avatar is given to it as its loader would have left it, and each strand ends in a
//! tail entity 7 cm below the last joint (bevy_vrm1 has no virtual tail; Tassel's last
//! joint swings toward the same point). As `VrmPlugin` does, the transforms are
//! propagated before bevy_vrm1's springs (it reads `GlobalTransform`s); its spring set
//! is put before Bevy's own propagation (so both apps propagate their simulated bones in
//! the same frame).
//!
//! Timed: the spring step itself (between two marker systems around
//! `TasselSystems::Step` and around `VrmSystemSets::SpringBone`), bevy_vrm1's step with
//! the propagation it needs before it, and the whole `App::update`. Medians over rounds
//! that alternate the apps, so that all see the same machine load: 25 rounds of 20 frames
//! by default (each app's round a fraction of a second, so that a slow spell of the
//! machine falls on every app; it was 5 rounds of 100 frames). The spread between runs
//! stays (on 2026-12-02, one build, two compute threads, `fixed`: 4.63–6.38× at 5 × 100,
//! 4.88–5.64× at 25 × 20): the crowd's solve waits on memory, whose speed moves more than
//! bevy_vrm1's step does. The plugin's own clock (`STEP_TIME`) is printed beside the
//! markers' time, with its parts.
//!
//! **`--avatar`: a real avatar with meshes.** Tassel's built-in character as a VRM 1.0 file
//! (`tassel_gltf::builtin_avatar()`: 82 joints and a skinned body, 13 springs of 44 joints,
//! 6 colliders), written to a temporary folder and loaded by Bevy's own glTF loader in
//! `DefaultPlugins` apps without a renderer (`RenderPlugin` with no wgpu backend: meshes
//! and skins are loaded, nothing is drawn), N copies swaying, each spawned as its glTF scene
//! would be (see `spawn_avatar`). Tassel gets the file through `SecondaryMotion` (the path
//! users take); bevy_vrm1 gets the springs as its components on the same entities (its own
//! loader needs its MToon renderer).
//!
//! **`--animated`**: every joint no spring moves (the body) is turned a little every frame
//! by a system in `Update`, in every app, as a clip would: the springs' input changes
//! each frame (without it only the roots move, and tassel-bevy's crowds read only the
//! bones whose `Transform` changed).
//!
//! Run from the repository root:
//! `cargo run --release --manifest-path bench/bevy_vrm1_vs_tassel/Cargo.toml -- [N] [--avatar] [--animated] [--frames F] [--rounds R] [--threads T] [--no-colliders]`
//! (`--threads`: Bevy's compute pool; its default on two cores is one thread).

use bevy::mesh::skinning::SkinnedMesh;
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use bevy::transform::systems::{propagate_parent_transforms, sync_simple_transforms};
use bevy::transform::TransformSystems;
use bevy_vrm1::prelude::{
    Capsule, ColliderShape, Sphere, SpringJointProps, SpringJoints, SpringRoot, VrmSystemSets,
};
use bevy_vrm1::vrm::spring_bone::{SpringCenterNode, SpringColliders, VrmSpringBonePlugin};
use std::time::{Duration, Instant};
use tassel::dynamics::vrm::{VrmShape, VrmSpringBones, VrmTail};
use tassel::dynamics::SimMode;
use tassel::Skeleton;
use tassel_bevy::prelude::*;

#[derive(Clone, Copy, PartialEq, Debug)]
enum Engine {
    TasselFixed,
    TasselSpec,
    BevyVrm1,
    Nothing,
}

/// Sways its entity, `.0` seconds ahead on the motion (the `crowd` example's motion).
#[derive(Component)]
struct Sway(f32);

fn sway(time: Res<Time>, mut q: Query<(&mut Transform, &Sway)>) {
    for (mut t, s) in &mut q {
        let x = time.elapsed_secs() + s.0;
        t.translation.x = 0.3 * (2.0 * x).sin();
        t.rotation = Quat::from_rotation_y(0.5 * (1.3 * x).sin());
    }
}

/// `--animated`: the joints no spring moves, with their rest rotations, turned a little
/// every frame before the springs run (as a clip playing on the body would).
#[derive(Resource, Default)]
struct Animate(Vec<(Entity, Quat)>);

fn animate(time: Res<Time>, a: Res<Animate>, mut q: Query<&mut Transform>) {
    let x = time.elapsed_secs();
    for (k, &(e, rest)) in a.0.iter().enumerate() {
        if let Ok(mut t) = q.get_mut(e) {
            t.rotation = rest * Quat::from_rotation_x(0.05 * (2.0 * x + 0.1 * k as f32).sin());
        }
    }
}

/// When the timed part of the frame began and ended.
#[derive(Resource, Default)]
struct Marks {
    before_propagation: Option<Instant>,
    start: Option<Instant>,
    end: Option<Instant>,
}

fn mark_before_propagation(mut m: ResMut<Marks>) {
    m.before_propagation = Some(Instant::now());
}
fn mark_start(mut m: ResMut<Marks>) {
    m.start = Some(Instant::now());
}
fn mark_end(mut m: ResMut<Marks>) {
    m.end = Some(Instant::now());
}

/// Each avatar's joint entities (the skeleton's order), for the comparison at the end.
#[derive(Resource, Default)]
struct Avatars(Vec<Vec<Entity>>);

fn app(engine: Engine, threads: Option<usize>, avatar_folder: Option<&str>) -> App {
    let mut tasks = TaskPoolPlugin::default();
    if let Some(n) = threads {
        tasks.task_pool_options.compute.min_threads = n;
        tasks.task_pool_options.compute.max_threads = n;
    }
    let mut app = App::new();
    match avatar_folder {
        None => {
            app.add_plugins((
                MinimalPlugins.set(tasks),
                AssetPlugin::default(),
                TransformPlugin,
            ));
        }
        Some(folder) => {
            use bevy::render::settings::WgpuSettings;
            use bevy::render::RenderPlugin;
            app.add_plugins(
                DefaultPlugins
                    .set(tasks)
                    .set(AssetPlugin {
                        file_path: folder.to_string(),
                        ..default()
                    })
                    .set(RenderPlugin {
                        render_creation: WgpuSettings {
                            backends: None,
                            ..default()
                        }
                        .into(),
                        ..default()
                    })
                    .disable::<bevy::log::LogPlugin>(),
            );
        }
    }
    app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
        1.0 / 60.0,
    )))
    .init_resource::<Marks>()
    .init_resource::<Avatars>()
    .init_resource::<Animate>()
    .add_systems(Update, (sway, animate));
    match engine {
        Engine::TasselFixed | Engine::TasselSpec => {
            app.add_plugins(TasselPlugin).add_systems(
                PostUpdate,
                (
                    mark_start
                        .after(TasselSystems::Bind)
                        .before(TasselSystems::Step),
                    mark_end.after(TasselSystems::Step),
                ),
            );
        }
        Engine::BevyVrm1 => {
            app.add_plugins(VrmSpringBonePlugin)
                // As `VrmPlugin` adds them: fresh `GlobalTransform`s for the springs.
                .add_systems(
                    PostUpdate,
                    (sync_simple_transforms, propagate_parent_transforms)
                        .chain()
                        .in_set(VrmSystemSets::PropagateAfterExpressions)
                        .before(VrmSystemSets::SpringBone),
                )
                .configure_sets(
                    PostUpdate,
                    VrmSystemSets::SpringBone.before(TransformSystems::Propagate),
                )
                .add_systems(
                    PostUpdate,
                    (
                        mark_before_propagation.before(VrmSystemSets::PropagateAfterExpressions),
                        mark_start
                            .after(VrmSystemSets::PropagateAfterExpressions)
                            .before(VrmSystemSets::SpringBone),
                        mark_end
                            .after(VrmSystemSets::SpringBone)
                            .before(TransformSystems::Propagate),
                    ),
                );
        }
        Engine::Nothing => {}
    }
    app
}

/// The mode a Tassel app runs in.
fn mode_of(engine: Engine) -> SimMode {
    if engine == Engine::TasselSpec {
        SimMode::Spec
    } else {
        SimMode::Fixed
    }
}

/// N avatars: the skeleton as named entities under a swaying root, with each engine's
/// components. Returns the number of simulated joints per avatar.
fn spawn(app: &mut App, engine: Engine, n: usize, sk: &Skeleton, vrm: &VrmSpringBones) -> usize {
    let model = (engine == Engine::TasselFixed || engine == Engine::TasselSpec).then(|| {
        app.world_mut()
            .resource_mut::<Assets<TasselModel>>()
            .add(TasselModel::new(sk.clone(), Some(vrm.clone())))
    });
    let mut avatars = Vec::with_capacity(n);
    for i in 0..n {
        let mut root = app
            .world_mut()
            .spawn((Transform::default(), Sway(0.37 * i as f32)));
        if let Some(model) = &model {
            root.insert(SecondaryMotion::new(model.clone()).with_mode(mode_of(engine)));
        }
        let root = root.id();
        let entities = tassel_bevy::spawn_skeleton(app.world_mut(), &sk, root);
        if engine == Engine::BevyVrm1 {
            add_bevy_vrm1_springs(app, vrm, &entities);
        }
        avatars.push(entities);
    }
    app.world_mut().resource_mut::<Avatars>().0 = avatars;
    vrm.springs.iter().map(|s| s.joints.len()).sum()
}

/// N copies of the avatar file under swaying roots, spawned as its glTF scene would be
/// (Bevy 0.19's scene spawner refuses this file's scene in an app without a render app:
/// "world contains the unregistered type"): the file's nodes as named entities (its 82
/// joints by `tassel_bevy::spawn_skeleton`, and its `body` node), under `body` one entity
/// per primitive with the file's `Mesh3d` and a `SkinnedMesh` on the joints, all loaded
/// by Bevy's glTF loader. Tassel gets the file through `SecondaryMotion` (its springs read
/// by Tassel, the path users take); bevy_vrm1 gets the springs as its components. Updates
/// until the file is loaded (and, for Tassel, every character bound). Returns the simulated
/// joints per avatar.
fn spawn_avatar(
    app: &mut App,
    engine: Engine,
    n: usize,
    sk: &Skeleton,
    vrm: &VrmSpringBones,
) -> usize {
    let tassel = engine == Engine::TasselFixed || engine == Engine::TasselSpec;
    let assets = app.world().resource::<AssetServer>().clone();
    let file: Handle<bevy::gltf::Gltf> = assets.load("avatar.vrm");
    let mut loaded = None;
    for _ in 0..2000 {
        app.update();
        let w = app.world();
        let (Some(gltf), meshes, skins) = (
            w.resource::<Assets<bevy::gltf::Gltf>>().get(&file),
            w.resource::<Assets<bevy::gltf::GltfMesh>>(),
            w.resource::<Assets<bevy::gltf::GltfSkin>>(),
        ) else {
            continue;
        };
        let nodes = w.resource::<Assets<bevy::gltf::GltfNode>>();
        let (Some(mesh), Some(skin)) = (meshes.get(&gltf.meshes[0]), skins.get(&gltf.skins[0]))
        else {
            continue;
        };
        let joints: Option<Vec<usize>> = skin
            .joints
            .iter()
            .map(|h| nodes.get(h).map(|n| n.index))
            .collect();
        let Some(joints) = joints else { continue };
        let prims: Vec<Handle<Mesh>> = mesh.primitives.iter().map(|p| p.mesh.clone()).collect();
        loaded = Some((prims, skin.inverse_bind_matrices.clone(), joints));
        break;
    }
    let (prims, bindposes, skin_joints) = loaded.expect("avatar.vrm loaded within 2000 frames");
    let model = tassel.then(|| assets.load::<TasselModel>("avatar.vrm"));
    let mut avatars = Vec::with_capacity(n);
    for i in 0..n {
        let mut root = app.world_mut().spawn((
            Transform::default(),
            Visibility::default(),
            Sway(0.37 * i as f32),
        ));
        if let Some(model) = &model {
            root.insert(SecondaryMotion::new(model.clone()).with_mode(mode_of(engine)));
        }
        let root = root.id();
        let entities = tassel_bevy::spawn_skeleton(app.world_mut(), sk, root);
        let w = app.world_mut();
        let body = w
            .spawn((
                Name::new("body"),
                Transform::default(),
                Visibility::default(),
                ChildOf(root),
            ))
            .id();
        let joints: Vec<Entity> = skin_joints.iter().map(|&j| entities[j]).collect();
        for mesh in &prims {
            w.spawn((
                Mesh3d(mesh.clone()),
                SkinnedMesh {
                    inverse_bindposes: bindposes.clone(),
                    joints: joints.clone(),
                },
                Transform::default(),
                Visibility::default(),
                ChildOf(body),
            ));
        }
        avatars.push(entities);
    }
    if tassel {
        let mut bound = 0;
        for _ in 0..2000 {
            app.update();
            let w = app.world_mut();
            bound = w.query::<&TasselCharacter>().iter(w).count();
            if bound == n {
                break;
            }
        }
        assert_eq!(bound, n, "every character bound within 2000 frames");
    }
    if engine == Engine::BevyVrm1 {
        for entities in &avatars {
            add_bevy_vrm1_springs(app, vrm, entities);
        }
    }
    let per_avatar = {
        let w = app.world_mut();
        w.query::<&ChildOf>().iter(w).count() / n
    };
    println!(
        "{engine:?}: {n} avatars, {per_avatar} entities below each root ({} primitives)",
        prims.len()
    );
    app.world_mut().resource_mut::<Avatars>().0 = avatars;
    vrm.springs.iter().map(|s| s.joints.len()).sum()
}

/// The avatar's springs as bevy_vrm1's components (what its loader inserts).
fn add_bevy_vrm1_springs(app: &mut App, vrm: &VrmSpringBones, entities: &[Entity]) {
    let colliders: Vec<(Entity, ColliderShape)> = vrm
        .colliders
        .iter()
        .map(|c| match c.shape {
            VrmShape::Sphere { offset, radius, .. } => (
                entities[c.joint],
                ColliderShape::Sphere(Sphere {
                    offset: offset.to_array(),
                    radius,
                }),
            ),
            VrmShape::Capsule {
                offset,
                tail,
                radius,
                ..
            } => (
                entities[c.joint],
                ColliderShape::Capsule(Capsule {
                    offset: offset.to_array(),
                    radius,
                    tail: tail.to_array(),
                }),
            ),
            VrmShape::Plane { .. } => unreachable!("the bench avatar has no plane"),
        })
        .collect();
    for spring in &vrm.springs {
        let mut joints: Vec<Entity> = spring.joints.iter().map(|j| entities[j.joint]).collect();
        // bevy_vrm1 swings a joint toward the next entity of the list: the last joint's
        // tail is an entity of its own.
        let last = spring.joints.last().expect("a strand has joints");
        match last.tail {
            VrmTail::Local(offset) => {
                let tail = app
                    .world_mut()
                    .spawn((
                        Name::new("tail"),
                        Transform::from_translation(offset),
                        ChildOf(entities[last.joint]),
                    ))
                    .id();
                joints.push(tail);
            }
            VrmTail::Joint(t) => joints.push(entities[t]),
        }
        for j in &spring.joints {
            app.world_mut()
                .entity_mut(entities[j.joint])
                .insert(SpringJointProps {
                    drag_force: j.drag_force,
                    gravity_dir: j.gravity_dir,
                    gravity_power: j.gravity_power,
                    hit_radius: j.hit_radius,
                    stiffness: j.stiffness,
                });
        }
        // The colliders of the spring's groups, as the loader lists them.
        let own: Vec<(Entity, ColliderShape)> = spring
            .collider_groups
            .iter()
            .flat_map(|&g| vrm.collider_groups[g].colliders.iter())
            .map(|&c| colliders[c].clone())
            .collect();
        app.world_mut().entity_mut(joints[0]).insert(SpringRoot {
            joints: SpringJoints(joints),
            colliders: SpringColliders(own),
            center_node: SpringCenterNode(None),
        });
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Per frame: (whole update, timed step, step with the propagation before it), ms.
fn run(app: &mut App, frames: usize, out: &mut [Vec<f64>; 3]) {
    for _ in 0..frames {
        let t = Instant::now();
        app.update();
        let whole = t.elapsed().as_secs_f64() * 1e3;
        let m = app.world().resource::<Marks>();
        let ms = |a: Option<Instant>, b: Option<Instant>| match (a, b) {
            (Some(a), Some(b)) => b.duration_since(a).as_secs_f64() * 1e3,
            _ => f64::NAN,
        };
        out[0].push(whole);
        out[1].push(ms(m.start, m.end));
        out[2].push(ms(m.before_propagation.or(m.start), m.end));
    }
}

fn main() {
    let mut n = 1000usize;
    let mut frames = 20usize;
    let mut rounds = 25usize;
    let mut threads = None;
    let mut colliders = true;
    let mut avatar = false;
    let mut animated = false;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || -> usize {
            args.next()
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("{a} needs a number"))
        };
        match a.as_str() {
            "--frames" => frames = value(),
            "--rounds" => rounds = value(),
            "--threads" => threads = Some(value()),
            "--no-colliders" => colliders = false,
            "--avatar" => avatar = true,
            "--animated" => animated = true,
            _ => n = a.parse().unwrap_or_else(|_| panic!("unknown argument {a}")),
        }
    }
    let (sk, mut vrm) = if avatar {
        let c = tassel::builtin::character();
        let springs = tassel::builtin::avatar::spring_bones(&c);
        (c.skeleton, springs)
    } else {
        tassel::builtin::bench_vrm(2, 9, 4)
    };
    // The avatar's file, for Bevy's asset server.
    let folder = std::env::temp_dir().join(format!("tassel-bevy-bench-{}", std::process::id()));
    if avatar {
        std::fs::create_dir_all(&folder).expect("a temporary folder");
        let bytes = tassel_gltf::builtin_avatar().expect("the built-in avatar");
        std::fs::write(folder.join("avatar.vrm"), bytes).expect("avatar.vrm written");
    }
    let folder_name = folder.to_string_lossy().into_owned();
    if !colliders {
        vrm.colliders.clear();
        vrm.collider_groups.clear();
        for s in &mut vrm.springs {
            s.collider_groups.clear();
        }
    }
    let engines = [
        Engine::TasselFixed,
        Engine::TasselSpec,
        Engine::BevyVrm1,
        Engine::Nothing,
    ];
    let mut apps: Vec<App> = Vec::new();
    let mut joints = 0;
    for &e in &engines {
        let mut a = app(e, threads, avatar.then_some(folder_name.as_str()));
        if avatar {
            a.finish();
            a.cleanup();
            joints = spawn_avatar(&mut a, e, n, &sk, &vrm);
        } else {
            joints = spawn(&mut a, e, n, &sk, &vrm);
        }
        if animated {
            let springs: std::collections::HashSet<usize> = vrm
                .springs
                .iter()
                .flat_map(|s| s.joints.iter().map(|j| j.joint))
                .collect();
            let driven: Vec<(Entity, Quat)> = a
                .world()
                .resource::<Avatars>()
                .0
                .iter()
                .flat_map(|e| {
                    (1..sk.len())
                        .filter(|j| !springs.contains(j))
                        .map(|j| (e[j], sk.rest()[j].rotation))
                })
                .collect();
            a.world_mut().resource_mut::<Animate>().0 = driven;
        }
        // Bound, initialised and warm.
        for _ in 0..30 {
            a.update();
        }
        apps.push(a);
    }
    let tassel_bound = |a: &mut App| {
        let w = a.world_mut();
        w.query::<&TasselCharacter>()
            .iter(w)
            .filter(|c| c.in_crowd())
            .count()
    };
    for a in &mut apps[..2] {
        assert_eq!(tassel_bound(a), n, "every Tassel character in its crowd");
    }
    let mut times: Vec<[Vec<f64>; 3]> = engines.iter().map(|_| Default::default()).collect();
    for _ in 0..rounds {
        for (a, t) in apps.iter_mut().zip(&mut times) {
            run(a, frames, t);
        }
    }
    // Both follow the specification: after the same frames, Tassel's `spec` mode and
    // bevy_vrm1 should agree on where the springs point.
    let rotations = |a: &mut App| -> Vec<Quat> {
        let avatars = std::mem::take(&mut a.world_mut().resource_mut::<Avatars>().0);
        let w = a.world_mut();
        let mut q = w.query::<&Transform>();
        let r = avatars
            .iter()
            .flat_map(|e| {
                vrm.springs
                    .iter()
                    .flat_map(move |s| s.joints.iter().map(move |j| e[j.joint]))
            })
            .map(|e| q.get(w, e).expect("a joint").rotation)
            .collect();
        a.world_mut().resource_mut::<Avatars>().0 = avatars;
        r
    };
    let (spec, theirs) = (rotations(&mut apps[1]), rotations(&mut apps[2]));
    let angles: Vec<f32> = spec
        .iter()
        .zip(&theirs)
        .map(|(a, b)| a.angle_between(*b))
        .collect();
    let worst = angles.iter().copied().fold(0.0f32, f32::max);
    let names: Vec<&str> = vrm
        .springs
        .iter()
        .flat_map(|s| s.joints.iter().map(|j| sk.name(j.joint)))
        .collect();
    if let Some(k) = angles.iter().position(|&a| a == worst) {
        println!("largest difference at joint '{}'", names[k % names.len()]);
    }
    let swing = spec
        .iter()
        .zip(
            &vrm.springs
                .iter()
                .flat_map(|s| s.joints.iter().map(|j| sk.rest()[j.joint].rotation))
                .cycle()
                .take(spec.len())
                .collect::<Vec<_>>(),
        )
        .map(|(a, b)| a.angle_between(*b))
        .fold(0.0f32, f32::max);

    let m: Vec<[f64; 3]> = times
        .into_iter()
        .map(|[a, b, c]| [median(a), median(b), median(c)])
        .collect();
    let per_joint = |ms: f64| ms * 1e6 / (n * joints) as f64;
    println!(
        "{n} {}{} x {joints} spring joints, {} colliders; {rounds} rounds x {frames} frames, apps alternating; {} compute threads; medians",
        if avatar { "copies of the built-in avatar (avatar.vrm, skinned, DefaultPlugins without a renderer)" } else { "bare avatars" },
        if animated { ", the body animated" } else { "" },
        vrm.colliders.len(),
        bevy::tasks::ComputeTaskPool::get().thread_num()
    );
    println!("| app | spring step, ms per frame | ns per joint-step | whole frame, ms |");
    println!("|---|---|---|---|");
    for (e, [whole, step, with_prop]) in engines.iter().zip(&m) {
        match e {
            Engine::Nothing => println!("| no secondary motion | - | - | {whole:.3} |"),
            Engine::BevyVrm1 => println!(
                "| bevy_vrm1 0.10 `update_spring_bones` (+ the propagation it needs before it) | {step:.3} ({with_prop:.3}) | {:.1} ({:.1}) | {whole:.3} |",
                per_joint(*step),
                per_joint(*with_prop)
            ),
            _ => println!(
                "| tassel-bevy, `{}` | {step:.3} | {:.1} | {whole:.3} |",
                if *e == Engine::TasselFixed { "fixed" } else { "spec" },
                per_joint(*step)
            ),
        }
    }
    // The plugin's own split of its step (its diagnostics' averages over their history:
    // the last frames of the last round).
    for (a, name) in apps[..2].iter().zip(["fixed", "spec"]) {
        if let Some(store) = a
            .world()
            .get_resource::<bevy::diagnostic::DiagnosticsStore>()
        {
            let avg = |p| {
                store
                    .get(p)
                    .and_then(|d: &bevy::diagnostic::Diagnostic| d.average())
                    .unwrap_or(f64::NAN)
            };
            println!(
                "tassel-bevy `{name}` split: step {:.3} ms (its own clock) = read {:.3} ms, solve {:.3} ms, write {:.3} ms",
                avg(&tassel_bevy::STEP_TIME),
                avg(&tassel_bevy::READ_TIME),
                avg(&tassel_bevy::SOLVE_TIME),
                avg(&tassel_bevy::WRITE_TIME)
            );
        }
    }
    let ratio = |i: usize| m[2][1] / m[i][1];
    let ratio_prop = |i: usize| m[2][2] / m[i][1];
    println!(
        "tassel-bevy per joint: fixed {:.2}x, spec {:.2}x bevy_vrm1's spring system ({:.2}x / {:.2}x with its propagation)",
        ratio(0),
        ratio(1),
        ratio_prop(0),
        ratio_prop(1)
    );
    println!(
        "whole frame against no secondary motion: tassel fixed {:.2}x, spec {:.2}x, bevy_vrm1 {:.2}x",
        m[0][0] / m[3][0],
        m[1][0] / m[3][0],
        m[2][0] / m[3][0]
    );
    println!(
        "tassel `spec` vs bevy_vrm1 after {} frames: largest angle between their joint rotations {worst:.2e} rad (the joints swing up to {swing:.2} rad from rest)",
        30 + rounds * frames
    );
}
