//! Criterion bench: one `App::update` of a headless Bevy app (MinimalPlugins, transforms)
//! with N copies of the bench avatar (two strands of eight VRM spring joints, four sphere
//! colliders) swaying, with and without the plugin, `fixed` and `spec` stepping, the
//! crowd path and one `CharacterSim` each. Throughput per simulated joint. The same
//! frame as `cargo run --release -p tassel-bevy --example crowd`, which also prints the
//! plugin's own share (its step diagnostics).

use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::time::Duration;
use tassel::dynamics::SimMode;
use tassel_bevy::prelude::*;

#[derive(Component)]
struct Sway(f32);

fn sway(time: Res<Time>, mut q: Query<(&mut Transform, &Sway)>) {
    for (mut t, s) in &mut q {
        let x = time.elapsed_secs() + s.0;
        t.translation.x = 0.3 * (2.0 * x).sin();
        t.rotation = Quat::from_rotation_y(0.5 * (1.3 * x).sin());
    }
}

/// `n` swaying avatars, each with `motion` (none: no secondary motion); returns the app
/// after every character started, and the simulated joints per avatar.
fn app(n: usize, motion: Option<(SimMode, bool)>) -> (App, usize) {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, AssetPlugin::default(), TransformPlugin))
        .insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(
            1.0 / 60.0,
        )))
        .add_plugins(TasselPlugin)
        .add_systems(Update, sway);
    let (skeleton, vrm) = tassel::builtin::bench_vrm(2, 9, 4);
    let joints = vrm.springs.iter().map(|s| s.joints.len()).sum();
    let model = app
        .world_mut()
        .resource_mut::<Assets<TasselModel>>()
        .add(TasselModel::new(skeleton.clone(), Some(vrm)));
    for i in 0..n {
        let mut root = app
            .world_mut()
            .spawn((Transform::default(), Sway(0.37 * i as f32)));
        if let Some((mode, crowd)) = motion {
            let m = SecondaryMotion::new(model.clone()).with_mode(mode);
            root.insert(if crowd { m } else { m.without_crowd() });
        }
        let root = root.id();
        tassel_bevy::spawn_skeleton(app.world_mut(), &skeleton, root);
    }
    for _ in 0..10 {
        app.update();
    }
    if motion.is_some() {
        let w = app.world_mut();
        assert_eq!(w.query::<&TasselCharacter>().iter(w).count(), n);
    }
    (app, joints)
}

fn plugin_frame(c: &mut Criterion) {
    let mut g = c.benchmark_group("bevy_frame");
    g.sample_size(20);
    let cases: [(&str, Option<(SimMode, bool)>); 4] = [
        ("no_secondary_motion", None),
        ("crowd_fixed", Some((SimMode::Fixed, true))),
        ("crowd_spec", Some((SimMode::Spec, true))),
        ("own_sims_fixed", Some((SimMode::Fixed, false))),
    ];
    for n in [100, 1000] {
        for (name, motion) in cases {
            let (mut app, joints) = app(n, motion);
            g.throughput(Throughput::Elements((n * joints) as u64));
            g.bench_function(format!("{n}_avatars_{name}"), |b| b.iter(|| app.update()));
        }
    }
    g.finish();
}

criterion_group!(benches, plugin_frame);
criterion_main!(benches);
