//! The seed's locomotion graph against a transcription of the seed's own switch statement,
//! plus cross-fades, events, triggers and bad definitions.

use tassel::anim::{BlendPlan, StateMachine};

const CLIPS: [&str; 6] = ["idle", "walk", "run", "jump_start", "jump_loop", "jump_end"];
const DURATIONS: [f32; 6] = [2.0, 1.0, 0.7, 0.45, 0.5, 0.3];

/// Seed 003's `AnimationFSM::update`, transcribed: the independent reference.
fn seed_next(state: &str, moving: bool, jumping: bool, finished: bool) -> &'static str {
    match state {
        "idle" if jumping => "jump_start_from_idle",
        "idle" if moving => "walk_run",
        "idle" => "idle",
        "walk_run" if jumping => "jump_start_from_walk_run",
        "walk_run" if !moving => "idle",
        "walk_run" => "walk_run",
        "jump_start_from_idle" if finished => "jump_loop_from_idle",
        "jump_start_from_idle" => "jump_start_from_idle",
        "jump_loop_from_idle" if !jumping => "jump_end_from_idle",
        "jump_loop_from_idle" => "jump_loop_from_idle",
        "jump_end_from_idle" if finished => "idle",
        "jump_end_from_idle" => "jump_end_from_idle",
        "jump_start_from_walk_run" if finished => "jump_loop_from_walk_run",
        "jump_start_from_walk_run" => "jump_start_from_walk_run",
        "jump_loop_from_walk_run" if !jumping => "jump_end_from_walk_run",
        "jump_loop_from_walk_run" => "jump_loop_from_walk_run",
        "jump_end_from_walk_run" if finished => "walk_run",
        "jump_end_from_walk_run" => "jump_end_from_walk_run",
        other => panic!("unknown state {other}"),
    }
}

#[test]
fn every_seed_transition_fires_on_its_signals_and_only_then() {
    let sm = StateMachine::from_toml_str(StateMachine::LOCOMOTION, &CLIPS, &DURATIONS).unwrap();
    let speed = sm.param("speed").unwrap();
    let jumping = sm.param("jumping").unwrap();
    let mut plan = BlendPlan::default();
    let mut checked = 0;
    for s in 0..sm.state_count() {
        for moving in [false, true] {
            for jump in [false, true] {
                for finished in [false, true] {
                    let mut st = sm.new_state();
                    st.set_state(s);
                    st.set(speed, if moving { 2.0 } else { 0.0 });
                    st.set(jumping, if jump { 1.0 } else { 0.0 });
                    // A step past the end of every one-shot clip, or a tiny one.
                    sm.update(&mut st, if finished { 1.0 } else { 0.001 }, &mut plan);
                    let from = sm.state_name(s);
                    let want = seed_next(from, moving, jump, finished);
                    assert_eq!(
                        sm.state_name(plan.state),
                        want,
                        "from {from}, moving {moving}, jumping {jump}, finished {finished}"
                    );
                    assert_eq!(plan.transitioned, want != from);
                    checked += 1;
                }
            }
        }
    }
    assert_eq!(checked, 8 * 8);
}

#[test]
fn cross_fade_and_events() {
    let sm = StateMachine::from_toml_str(StateMachine::LOCOMOTION, &CLIPS, &DURATIONS).unwrap();
    let mut st = sm.new_state();
    let mut plan = BlendPlan::default();
    st.set(sm.param("jumping").unwrap(), 1.0);
    sm.update(&mut st, 1.0 / 60.0, &mut plan);
    assert_eq!(plan.events, ["jump"]);
    // During the 0.1 s fade the new state's weight rises linearly and weights sum to 1.
    for f in 1..=5 {
        sm.update(&mut st, 0.02, &mut plan);
        let total: f32 = plan.layers.iter().map(|l| l.weight).sum();
        assert!((total - 1.0).abs() < 1e-5);
        let new_w: f32 = plan
            .layers
            .iter()
            .filter(|l| l.clip == 3)
            .map(|l| l.weight)
            .sum();
        assert!(
            (new_w - (0.02 * f as f32 / 0.1).min(1.0)).abs() < 1e-4,
            "frame {f}: {new_w}"
        );
        assert!(plan.events.is_empty());
    }
    assert_eq!(plan.layers.len(), 1, "fade over");
    // walk_run at 2.7 m/s blends walk and run half and half, phase-synchronised.
    let mut st = sm.new_state();
    st.set(sm.param("speed").unwrap(), 2.7);
    for _ in 0..60 {
        sm.update(&mut st, 1.0 / 60.0, &mut plan);
    }
    let w: Vec<(usize, f32)> = plan.layers.iter().map(|l| (l.clip, l.weight)).collect();
    assert_eq!(w.len(), 2, "{w:?}");
    assert!(
        w.iter()
            .all(|&(c, x)| (c == 1 || c == 2) && (x - 0.5).abs() < 1e-5),
        "{w:?}"
    );
    let (a, b) = (plan.layers[0], plan.layers[1]);
    assert!(
        (a.time / DURATIONS[a.clip] - b.time / DURATIONS[b.clip]).abs() < 1e-5,
        "same phase"
    );
}

#[test]
fn triggers_are_consumed_and_bad_definitions_named() {
    let def = r#"
[parameters]
wave = { type = "trigger" }
[[state]]
name = "a"
clip = "idle"
[[state]]
name = "b"
clip = "walk"
[[transition]]
from = "a"
to = "b"
when = ["wave"]
[[transition]]
from = "b"
to = "a"
when = ["wave"]
"#;
    let sm = StateMachine::from_toml_str(def, &CLIPS, &DURATIONS).unwrap();
    let mut st = sm.new_state();
    let mut plan = BlendPlan::default();
    st.fire(sm.param("wave").unwrap());
    sm.update(&mut st, 0.01, &mut plan);
    assert_eq!(sm.state_name(plan.state), "b");
    sm.update(&mut st, 0.01, &mut plan);
    assert_eq!(sm.state_name(plan.state), "b", "the trigger was used once");

    let cases = [
        (def.replace("clip = \"walk\"", "clip = \"swim\""), "swim"),
        (
            def.replace(
                "when = [\"wave\"]\n[[transition]]",
                "when = [\"wav\"]\n[[transition]]",
            ),
            "wav",
        ),
        (def.replace("name = \"b\"", "name = \"a\""), "two states"),
        (
            def.replace("to = \"b\"", "to = \"c\""),
            "no state named 'c'",
        ),
    ];
    for (text, needle) in cases {
        let e = StateMachine::from_toml_str(&text, &CLIPS, &DURATIONS)
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "'{e}' should mention '{needle}'");
    }
}
