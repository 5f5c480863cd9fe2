//! The animator: a state machine's plan sampled and blended, with root motion taken out of
//! the pose and reported as a blended delta.

use glam::Vec3;
use tassel::anim::{Animator, Clip, RootMotion, StateMachine};
use tassel::Transform;

fn mover(name: &str, speed: f32, duration: f32) -> Clip {
    let keys = (0..=10).map(|k| {
        let t = k as f32 * duration / 10.0;
        (t, Vec3::new(0.0, 1.0, speed * t))
    });
    Clip::linear_translation(name, duration, 0, keys)
}

#[test]
fn blended_root_motion_matches_the_phase_synchronised_speed() {
    let clips = vec![
        mover("idle", 0.0, 2.0),
        mover("walk", 1.4, 1.0),
        mover("run", 4.0, 0.7),
        mover("jump_start", 0.0, 0.45),
        mover("jump_loop", 0.0, 0.45),
        mover("jump_end", 0.0, 0.3),
    ];
    let names: Vec<&str> = clips.iter().map(|c| c.name.as_str()).collect();
    let durations: Vec<f32> = clips.iter().map(|c| c.duration).collect();
    let sm = StateMachine::from_toml_str(StateMachine::LOCOMOTION, &names, &durations).unwrap();
    let mut anim = Animator::new(sm, &clips);
    anim.root_motion = Some(RootMotion {
        joint: 0,
        up: Vec3::Y,
    });
    let speed = anim.machine().param("speed").unwrap();
    anim.state.set(speed, 2.7);
    let rest = [Transform::IDENTITY];
    let mut out = [Transform::IDENTITY];
    let dt = 1.0 / 60.0;
    // Let the 0.25 s fade from idle finish, then measure 3 s.
    for _ in 0..30 {
        anim.update(&clips, &rest, dt, &mut out).unwrap();
    }
    let mut travel = Vec3::ZERO;
    for _ in 0..180 {
        anim.update(&clips, &rest, dt, &mut out).unwrap();
        travel += anim.root_motion_delta();
        // The pose keeps the root's height but not its travel.
        assert!(out[0].translation.z.abs() < 1e-5 && (out[0].translation.y - 1.0).abs() < 1e-5);
    }
    // By hand: at 2.7 m/s the space is half walk, half run; one shared cycle lasts
    // 0.5·1.0 + 0.5·0.7 = 0.85 s and travels 0.5·1.4 + 0.5·(4.0·0.7) = 2.1 m.
    let expected = 3.0 * 2.1 / 0.85;
    assert!(
        (travel.z - expected).abs() < 1e-3,
        "{} vs {expected}",
        travel.z
    );
    assert!(travel.x.abs() < 1e-6 && travel.y.abs() < 1e-6);
}
