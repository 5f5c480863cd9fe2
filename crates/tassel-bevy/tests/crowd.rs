//! The plugin's crowd path (characters of one kind stepped together, their bones read and
//! written in flat passes, all on Bevy's compute task pool) against characters of the
//! same kind on their own `CharacterSim` in the same app: the same bits, whatever the
//! number of threads; a bad bone holds only its character; a changed mode moves a
//! character to another crowd.

mod common;

use bevy::prelude::*;
use bevy::tasks::ComputeTaskPool;
use common::*;
use tassel::dynamics::SimMode;
use tassel_bevy::prelude::*;

/// Sways its entity, `.0` seconds ahead on the motion.
#[derive(Component)]
struct Sway(f32);

fn sway(time: Res<Time>, mut q: Query<(&mut Transform, &Sway)>) {
    for (mut t, s) in &mut q {
        let x = time.elapsed_secs() + s.0;
        t.translation.x = 0.3 * (2.0 * x).sin();
        t.rotation = Quat::from_rotation_y(0.5 * (1.3 * x).sin());
    }
}

/// One pair: a crowd member and its twin on its own sim, on the same phase of the sway.
struct Pair {
    crowd: Entity,
    twin: Entity,
    crowd_bones: Vec<Entity>,
    twin_bones: Vec<Entity>,
}

/// An app on `threads` compute threads with `pairs` pairs of the bench avatar (two
/// strands of eight VRM spring joints, four spheres) in `mode`.
fn crowd_app(threads: usize, pairs: usize, mode: SimMode) -> (App, Vec<Pair>, Vec<usize>) {
    let mut app = app_on_threads(60.0, threads);
    app.add_systems(Update, sway);
    let (skeleton, vrm) = tassel::builtin::bench_vrm(2, 9, 4);
    let simulated: Vec<usize> = vrm
        .springs
        .iter()
        .flat_map(|s| s.joints.iter().map(|j| j.joint))
        .collect();
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(skeleton.clone(), Some(vrm)));
    let mut spawn = |phase: f32, own: bool| {
        let m = SecondaryMotion::new(model.clone()).with_mode(mode);
        let m = if own { m.without_crowd() } else { m };
        let root = app
            .world_mut()
            .spawn((Transform::default(), Sway(phase), m))
            .id();
        let bones = spawn_skeleton(app.world_mut(), &skeleton, root);
        (root, bones)
    };
    let pairs = (0..pairs)
        .map(|i| {
            let phase = 0.37 * i as f32;
            let (crowd, crowd_bones) = spawn(phase, false);
            let (twin, twin_bones) = spawn(phase, true);
            Pair {
                crowd,
                twin,
                crowd_bones,
                twin_bones,
            }
        })
        .collect();
    (app, pairs, simulated)
}

fn bits(t: &Transform) -> [u32; 10] {
    let mut b = [0u32; 10];
    let v = t
        .translation
        .to_array()
        .into_iter()
        .chain(t.rotation.to_array())
        .chain(t.scale.to_array());
    for (k, x) in v.enumerate() {
        b[k] = x.to_bits();
    }
    b
}

/// Every crowd member's simulated bones have its twin's bits (checked); returns them,
/// and the largest swing of a simulated bone from its rest rotation.
fn compare(app: &App, pairs: &[Pair], simulated: &[usize], frame: usize) -> (Vec<[u32; 10]>, f32) {
    let world = app.world();
    let rest = tassel::builtin::bench_vrm(2, 9, 4).0;
    let mut out = Vec::new();
    let mut swing = 0.0f32;
    for (p, pair) in pairs.iter().enumerate() {
        for &j in simulated {
            let a = world.get::<Transform>(pair.crowd_bones[j]).unwrap();
            let b = world.get::<Transform>(pair.twin_bones[j]).unwrap();
            assert_eq!(
                bits(a),
                bits(b),
                "frame {frame}, pair {p}, joint {j}: crowd {a:?}, own sim {b:?}"
            );
            swing = swing.max(a.rotation.angle_between(rest.rest()[j].rotation));
            out.push(bits(a));
        }
    }
    (out, swing)
}

fn in_crowd(app: &App, e: Entity) -> bool {
    app.world().get::<TasselCharacter>(e).unwrap().in_crowd()
}

/// Set in the child processes of the thread-count test: how many compute threads.
const THREADS: &str = "TASSEL_TEST_COMPUTE_THREADS";

/// Bevy's task pools are made once per process, so each thread count runs in a child
/// process (this test binary, this test alone); each checks every crowd member against
/// its twin on its own sim, bit for bit, every frame, and prints a digest of every
/// simulated bone's bits over the run, which must be the same on 1 and 3 threads.
#[test]
fn crowd_bones_match_own_sims_on_one_and_three_threads() {
    const NAME: &str = "crowd_bones_match_own_sims_on_one_and_three_threads";
    if let Ok(n) = std::env::var(THREADS) {
        let threads: usize = n.parse().unwrap();
        for mode in [SimMode::Fixed, SimMode::Spec] {
            let (mut app, pairs, simulated) = crowd_app(threads, 20, mode);
            // FNV-1a over every compared bone's bits, frame after frame.
            let mut digest = 0xcbf2_9ce4_8422_2325u64;
            let mut swing = 0.0f32;
            for frame in 0..90 {
                app.update();
                if frame == 5 {
                    assert!(pairs.iter().all(|p| in_crowd(&app, p.crowd)));
                    assert!(pairs.iter().all(|p| !in_crowd(&app, p.twin)));
                }
                if frame >= 5 {
                    let (b, s) = compare(&app, &pairs, &simulated, frame);
                    for x in b.iter().flatten() {
                        digest = (digest ^ u64::from(*x)).wrapping_mul(0x100_0000_01b3);
                    }
                    swing = swing.max(s);
                }
            }
            assert!(swing > 0.1, "{mode:?}: the springs swing ({swing} rad)");
            println!(
                "digest {mode:?} threads={} {digest:016x}",
                ComputeTaskPool::get().thread_num()
            );
        }
        return;
    }
    let run = |threads: usize| -> Vec<String> {
        let out = std::process::Command::new(std::env::current_exe().unwrap())
            .args([NAME, "--exact", "--nocapture", "--test-threads", "1"])
            .env(THREADS, threads.to_string())
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{threads} threads: {stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        // (libtest may print the test's name on the same line as the first digest.)
        stdout
            .lines()
            .filter_map(|l| l.find("digest ").map(|k| l[k..].to_string()))
            .collect()
    };
    let (one, three) = (run(1), run(3));
    assert_eq!(one.len(), 2, "{one:?}");
    assert!(one.iter().all(|l| l.contains("threads=1 ")), "{one:?}");
    assert!(three.iter().all(|l| l.contains("threads=3 ")), "{three:?}");
    let strip = |v: &[String]| -> Vec<String> {
        v.iter()
            .map(|l| l.replace("threads=1 ", "").replace("threads=3 ", ""))
            .collect()
    };
    assert_eq!(strip(&one), strip(&three), "1 and 3 compute threads differ");
}

#[test]
fn a_bad_bone_holds_only_its_character_and_a_new_mode_moves_it_to_another_crowd() {
    let (mut app, pairs, simulated) = crowd_app(2, 20, SimMode::Fixed);
    // Pair 3's root bone (crowd member and twin) gets a NaN for one frame, after the
    // animation; the frame after, its pose is back.
    #[derive(Resource)]
    struct Poison(Vec<Entity>, usize, Vec<Quat>);
    fn poison(mut p: ResMut<Poison>, mut q: Query<&mut Transform>) {
        p.1 += 1;
        if p.1 == 30 {
            let kept = p.0.iter().map(|&e| q.get(e).unwrap().rotation).collect();
            p.2 = kept;
            for &e in &p.0 {
                q.get_mut(e).unwrap().rotation = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
            }
        }
        if p.1 == 31 {
            for (&e, &r) in p.0.iter().zip(&p.2) {
                q.get_mut(e).unwrap().rotation = r;
            }
        }
    }
    app.insert_resource(Poison(
        vec![pairs[3].crowd_bones[0], pairs[3].twin_bones[0]],
        0,
        Vec::new(),
    ))
    .add_systems(
        PostUpdate,
        poison
            .after(bevy::app::AnimationSystems)
            .before(TasselSystems::Step),
    );
    let mut swing = 0.0f32;
    for frame in 1..=100 {
        if frame == 60 {
            // Pair 5 to `spec`: the member leaves the fixed crowd for a spec crowd.
            for e in [pairs[5].crowd, pairs[5].twin] {
                app.world_mut().get_mut::<SecondaryMotion>(e).unwrap().mode = SimMode::Spec;
            }
        }
        app.update();
        if frame == 30 {
            let errors = &app.world().resource::<Errors>().0;
            let mut who: Vec<Entity> = errors.iter().map(|e| e.entity).collect();
            who.sort();
            let mut expected = vec![pairs[3].crowd, pairs[3].twin];
            expected.sort();
            assert_eq!(who, expected, "{errors:?}");
            assert!(errors.iter().all(|e| e.message.contains("not finite")));
            let c = app.world().get::<TasselCharacter>(pairs[3].crowd).unwrap();
            assert!(c.error().is_some());
        }
        if frame == 31 {
            let c = app.world().get::<TasselCharacter>(pairs[3].crowd).unwrap();
            assert!(c.error().is_none(), "recovered");
        }
        if frame > 3 {
            // Every pair, the poisoned one and the moved one included.
            swing = swing.max(compare(&app, &pairs, &simulated, frame).1);
        }
        if frame == 61 {
            let world = app.world();
            let c = world.get::<TasselCharacter>(pairs[5].crowd).unwrap();
            assert!(c.in_crowd(), "still in a crowd");
            assert_eq!(
                c.rig().vrm().options.mode,
                tassel::dynamics::vrm::VrmMode::Spec
            );
            let other = world.get::<TasselCharacter>(pairs[6].crowd).unwrap();
            assert!(
                !std::sync::Arc::ptr_eq(c.rig(), other.rig()),
                "another kind than the fixed crowd's"
            );
        }
    }
    assert!(swing > 0.1, "the springs swing ({swing} rad)");
    // Nothing else failed.
    assert_eq!(app.world().resource::<Errors>().0.len(), 2);
}

#[test]
fn members_despawned_and_spawned_mid_run_leave_and_join() {
    let (mut app, mut pairs, simulated) = crowd_app(2, 18, SimMode::Fixed);
    for frame in 1..=80 {
        if frame == 20 {
            // Despawn a member from the middle (the last member takes its index) and its
            // twin.
            let p = pairs.remove(7);
            app.world_mut().entity_mut(p.crowd).despawn();
            app.world_mut().entity_mut(p.twin).despawn();
        }
        app.update();
        if frame > 3 {
            compare(&app, &pairs, &simulated, frame);
        }
    }
}

#[test]
fn step_settings_on_secondary_motion_reach_the_springs() {
    let mut app = app(60.0);
    let (skeleton, vrm) = tassel::builtin::bench_vrm(2, 9, 4);
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(skeleton.clone(), Some(vrm)));
    let mut spawn = |m: SecondaryMotion| {
        let root = app.world_mut().spawn((Transform::default(), m)).id();
        spawn_skeleton(app.world_mut(), &skeleton, root);
        root
    };
    let set = spawn(
        SecondaryMotion::new(model.clone())
            .with_vrm_step_rate(30.0)
            .with_max_steps_per_frame(2),
    );
    let plain = spawn(SecondaryMotion::new(model.clone()));
    let bad = spawn(SecondaryMotion::new(model.clone()).with_vrm_step_rate(5.0));
    for _ in 0..3 {
        app.update();
    }
    let world = app.world();
    let a = world.get::<TasselCharacter>(set).unwrap();
    let b = world.get::<TasselCharacter>(plain).unwrap();
    let options = &a.rig().vrm().options;
    assert_eq!((options.step_rate, options.max_steps_per_frame), (30.0, 2));
    let defaults = &b.rig().vrm().options;
    assert_eq!(
        (defaults.step_rate, defaults.max_steps_per_frame),
        (60.0, 8)
    );
    assert!(!std::sync::Arc::ptr_eq(a.rig(), b.rig()), "two kinds");
    assert!(a.in_crowd() && b.in_crowd());
    let failed = world
        .get::<TasselFailed>(bad)
        .expect("a bad step rate fails");
    assert!(failed.0.contains("step_rate 5"), "{}", failed.0);
}

/// Two characters over one hierarchy (a `SecondaryMotion` on an entity and another on its
/// child, the bones below both): both step in one crowd and write the same bones, one
/// after the other (the parallel write needs each bone once), the same values, as twins
/// on their own sims write.
#[test]
fn two_characters_over_one_hierarchy_write_their_bones_in_turn() {
    let (mut app, pairs, simulated) = crowd_app(2, 2, SimMode::Fixed);
    let (skeleton, vrm) = tassel::builtin::bench_vrm(2, 9, 4);
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(skeleton.clone(), Some(vrm)));
    let outer = app
        .world_mut()
        .spawn((Transform::default(), SecondaryMotion::new(model.clone())))
        .id();
    let inner = app
        .world_mut()
        .spawn((
            Transform::default(),
            ChildOf(outer),
            SecondaryMotion::new(model.clone()),
        ))
        .id();
    let bones = spawn_skeleton(app.world_mut(), &skeleton, inner);
    let twin = app
        .world_mut()
        .spawn((
            Transform::default(),
            SecondaryMotion::new(model).without_crowd(),
        ))
        .id();
    let twin_bones = spawn_skeleton(app.world_mut(), &skeleton, twin);
    for frame in 0..40 {
        app.update();
        if frame > 3 {
            compare(&app, &pairs, &simulated, frame);
            let world = app.world();
            for &j in &simulated {
                let a = world.get::<Transform>(bones[j]).unwrap();
                let b = world.get::<Transform>(twin_bones[j]).unwrap();
                assert_eq!(bits(a), bits(b), "frame {frame}, joint {j}");
            }
        }
    }
    assert!(in_crowd(&app, outer) && in_crowd(&app, inner));
    assert!(app.world().resource::<Errors>().0.is_empty());
}

/// Crowd members read their animated bones by walking the bones whose `Transform` changed
/// since the plugin last ran (Bevy's change ticks); characters on their own sims look every
/// bone up and compare it with what they wrote. Both must see the same input: a bone
/// animated five frames in ten (the skeleton's root; in the other five no bone moves, so
/// the crowd members are marked unchanged and step on the pose their lane group kept), a
/// simulated bone animated for a while and
/// then left alone (its input stays its last animated pose, not the simulated one), and a
/// simulated bone set once.
#[test]
fn animated_bones_reach_crowd_members_as_they_reach_own_sims() {
    #[derive(Resource)]
    struct Drive {
        bones: Vec<Vec<Entity>>,
        joints: [usize; 2],
        frame: u32,
        on: bool,
    }
    fn drive(mut d: ResMut<Drive>, mut q: Query<&mut Transform>) {
        d.frame += 1;
        if !d.on {
            return;
        }
        let (f, [a, b]) = (d.frame as f32, d.joints);
        for bones in &d.bones {
            // Half the frames move no bone at all: the crowd members are then marked
            // unchanged, and their lane groups step on the pose they kept.
            if d.frame % 10 < 5 {
                q.get_mut(bones[0]).unwrap().rotation =
                    Quat::from_rotation_z(0.4 * (0.21 * f).sin());
            }
            if (20..40).contains(&d.frame) {
                q.get_mut(bones[a]).unwrap().rotation =
                    Quat::from_rotation_x(0.5 * (0.3 * f).sin());
            }
            if d.frame == 50 {
                q.get_mut(bones[b]).unwrap().rotation = Quat::from_rotation_z(0.6);
            }
        }
    }
    let run = |on: bool| -> u64 {
        let (mut app, pairs, simulated) = crowd_app(2, 6, SimMode::Fixed);
        let bones = pairs
            .iter()
            .flat_map(|p| [p.crowd_bones.clone(), p.twin_bones.clone()])
            .collect();
        app.insert_resource(Drive {
            bones,
            joints: [simulated[0], simulated[3]],
            frame: 0,
            on,
        })
        .add_systems(
            PostUpdate,
            drive
                .after(bevy::app::AnimationSystems)
                .before(TasselSystems::Step),
        );
        let mut digest = 0xcbf2_9ce4_8422_2325u64;
        for frame in 1..=90 {
            app.update();
            if frame > 3 {
                let (b, _) = compare(&app, &pairs, &simulated, frame);
                for x in b.iter().flatten() {
                    digest = (digest ^ u64::from(*x)).wrapping_mul(0x100_0000_01b3);
                }
            }
        }
        assert!(pairs.iter().all(|p| in_crowd(&app, p.crowd)));
        assert!(app.world().resource::<Errors>().0.is_empty());
        digest
    };
    assert_ne!(run(true), run(false), "the animation reaches the springs");
}
