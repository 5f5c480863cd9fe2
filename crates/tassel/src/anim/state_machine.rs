//! A data-driven animation state machine: states play a clip or a 1D blend space;
//! transitions fire on conditions over parameters (float, bool, trigger) and on
//! `clip_finished`, in priority (file) order, with a cross-fade and events out. The
//! definition is TOML (docs/state_machine.md); the seed's locomotion graph ships as
//! [`StateMachine::LOCOMOTION`].

use super::blend_space::{BlendSpace1D, BlendSpacePhase};
use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::BTreeMap;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Def {
    initial: Option<String>,
    #[serde(default)]
    parameters: BTreeMap<String, ParamDef>,
    #[serde(rename = "state")]
    states: Vec<StateDef>,
    #[serde(default, rename = "transition")]
    transitions: Vec<TransitionDef>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ParamDef {
    #[serde(rename = "type")]
    kind: String,
    #[serde(default)]
    default: Option<f32>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct StateDef {
    name: String,
    clip: Option<String>,
    blend_space: Option<SpaceDef>,
    #[serde(default = "yes", rename = "loop")]
    looping: bool,
    #[serde(default = "one")]
    speed: f32,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SpaceDef {
    parameter: String,
    clips: Vec<(f32, String)>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TransitionDef {
    from: String,
    to: String,
    #[serde(default)]
    when: Vec<String>,
    #[serde(default)]
    fade: f32,
    #[serde(default)]
    events: Vec<String>,
}

fn yes() -> bool {
    true
}
fn one() -> f32 {
    1.0
}

/// A parameter's kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// A number.
    Float,
    /// True or false.
    Bool,
    /// Set by [`StateMachineState::fire`], cleared when a transition uses it.
    Trigger,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
}

#[derive(Debug, Clone, PartialEq)]
enum Cond {
    ClipFinished,
    Flag { param: usize, value: bool },
    Compare { param: usize, op: Op, value: f32 },
}

#[derive(Debug, Clone, PartialEq)]
enum Motion {
    Clip { clip: usize, looping: bool },
    Space { space: BlendSpace1D, param: usize },
}

#[derive(Debug, Clone, PartialEq)]
struct State {
    name: String,
    motion: Motion,
    speed: f32,
}

#[derive(Debug, Clone, PartialEq)]
struct Transition {
    from: Option<usize>,
    to: usize,
    conds: Vec<Cond>,
    fade: f32,
    events: Vec<String>,
}

/// A compiled state machine (shareable between characters).
///
/// ```
/// use tassel::anim::{BlendPlan, StateMachine};
///
/// let toml = r#"
/// initial = "idle"
///
/// [parameters]
/// speed = { type = "float" }
///
/// [[state]]
/// name = "idle"
/// clip = "idle"
///
/// [[state]]
/// name = "walk"
/// clip = "walk"
///
/// [[transition]]
/// from = "idle"
/// to = "walk"
/// when = ["speed > 0.5"]
/// fade = 0.2
/// "#;
/// let machine = StateMachine::from_toml_str(toml, &["idle", "walk"], &[2.0, 1.0])?;
/// let mut state = machine.new_state();
/// let mut plan = BlendPlan::default();
/// machine.update(&mut state, 0.1, &mut plan);
/// assert_eq!(machine.state_name(plan.state), "idle");
///
/// state.set(machine.param("speed").unwrap(), 1.2);
/// machine.update(&mut state, 0.1, &mut plan);
/// assert_eq!(machine.state_name(plan.state), "walk");
/// assert!(plan.transitioned);
/// // 0.1 s into the 0.2 s fade: both clips play at half weight.
/// machine.update(&mut state, 0.1, &mut plan);
/// assert_eq!(plan.layers.len(), 2);
/// assert!(plan.layers.iter().all(|l| (l.weight - 0.5).abs() < 1e-6));
/// # Ok::<(), tassel::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct StateMachine {
    params: Vec<(String, ParamKind, f32)>,
    states: Vec<State>,
    transitions: Vec<Transition>,
    initial: usize,
    durations: Vec<f32>,
}

/// One clip to sample and its weight, the output of [`StateMachine::update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanLayer {
    /// Clip index.
    pub clip: usize,
    /// Time in the clip, seconds (already wrapped or clamped).
    pub time: f32,
    /// Weight; the layers of one plan sum to 1.
    pub weight: f32,
    /// Clip seconds played per second of this update (state speed, blend-space rate).
    pub rate: f32,
    /// The clip loops (time wraps) rather than holding its last pose.
    pub looping: bool,
}

/// What to play this frame.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlendPlan {
    /// Clips and weights.
    pub layers: Vec<PlanLayer>,
    /// Events of the transitions that fired this update.
    pub events: Vec<String>,
    /// The current state (index; see [`StateMachine::state_name`]).
    pub state: usize,
    /// True when a transition fired this update.
    pub transitioned: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Playing {
    state: usize,
    time: f32,
    phase: BlendSpacePhase,
}

/// The per-character state of a [`StateMachine`]: current state, fade and parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct StateMachineState {
    current: Playing,
    fading: Option<(Playing, f32, f32)>,
    values: Vec<f32>,
    weights: Vec<f32>,
}

impl StateMachineState {
    /// Sets a float or bool (non-zero = true) parameter by index.
    pub fn set(&mut self, param: usize, value: f32) {
        if let Some(v) = self.values.get_mut(param) {
            *v = value;
        }
    }

    /// Fires a trigger parameter (it stays set until a transition uses it).
    pub fn fire(&mut self, param: usize) {
        self.set(param, 1.0);
    }

    /// A parameter's value (bools and triggers as 0 or 1).
    pub fn value(&self, param: usize) -> f32 {
        self.values.get(param).copied().unwrap_or(0.0)
    }

    /// The current state's index.
    pub fn current(&self) -> usize {
        self.current.state
    }

    /// Jumps to `state` at its start, with no fade.
    pub fn set_state(&mut self, state: usize) {
        self.current = Playing {
            state,
            time: 0.0,
            phase: BlendSpacePhase::default(),
        };
        self.fading = None;
    }
}

fn parse_cond(text: &str, params: &[(String, ParamKind, f32)], what: &str) -> Result<Cond> {
    let bad = |m: String| Error::InvalidParameter(format!("{what}: condition '{text}': {m}"));
    let find = |name: &str| {
        params
            .iter()
            .position(|p| p.0 == name)
            .ok_or_else(|| bad(format!("no parameter named '{name}'")))
    };
    let t = text.trim();
    if t == "clip_finished" {
        return Ok(Cond::ClipFinished);
    }
    for (sym, op) in [
        ("<=", Op::Le),
        (">=", Op::Ge),
        ("==", Op::Eq),
        ("!=", Op::Ne),
        ("<", Op::Lt),
        (">", Op::Gt),
    ] {
        if let Some((l, r)) = t.split_once(sym) {
            let param = find(l.trim())?;
            let value: f32 = r
                .trim()
                .parse()
                .map_err(|_| bad(format!("'{}' is not a number", r.trim())))?;
            if params[param].1 != ParamKind::Float || !value.is_finite() {
                return Err(bad(
                    "comparisons need a float parameter and a finite number".into(),
                ));
            }
            return Ok(Cond::Compare { param, op, value });
        }
    }
    let (name, value) = match t.strip_prefix('!') {
        Some(n) => (n.trim(), false),
        None => (t, true),
    };
    let param = find(name)?;
    if params[param].1 == ParamKind::Float {
        return Err(bad(format!(
            "'{name}' is a float: compare it (e.g. '{name} > 0')"
        )));
    }
    Ok(Cond::Flag { param, value })
}

impl StateMachine {
    /// The seed's locomotion graph, as TOML. Needs clips named idle, walk, run,
    /// jump_start, jump_loop and jump_end; parameters `speed` (float) and `jumping` (bool).
    pub const LOCOMOTION: &'static str = include_str!("locomotion.toml");

    /// Compiles a TOML definition against the clips available (`clip_names[i]` has
    /// `durations[i]` seconds). Errors name the state, transition or clip.
    pub fn from_toml_str(text: &str, clip_names: &[&str], durations: &[f32]) -> Result<Self> {
        let def: Def = toml::from_str(text)
            .map_err(|e| Error::InvalidParameter(format!("state machine: {e}")))?;
        let max = crate::limits::MAX_STATES;
        for (what, n) in [
            ("parameters", def.parameters.len()),
            ("states", def.states.len()),
            ("transitions", def.transitions.len()),
        ] {
            if n > max {
                return Err(Error::InvalidParameter(format!(
                    "state machine: {n} {what}, more than the limit of {max}"
                )));
            }
        }
        let mut params = Vec::new();
        for (name, p) in &def.parameters {
            let kind = match p.kind.as_str() {
                "float" => ParamKind::Float,
                "bool" => ParamKind::Bool,
                "trigger" => ParamKind::Trigger,
                k => {
                    return Err(Error::InvalidParameter(format!(
                        "parameter '{name}': unknown type '{k}'"
                    )))
                }
            };
            let default = p.default.unwrap_or(0.0);
            if !default.is_finite() {
                return Err(Error::InvalidParameter(format!(
                    "parameter '{name}': default is not finite"
                )));
            }
            params.push((name.clone(), kind, default));
        }
        let clip = |name: &str, what: &str| {
            clip_names
                .iter()
                .position(|c| *c == name)
                .ok_or_else(|| Error::InvalidParameter(format!("{what}: no clip named '{name}'")))
        };
        let mut states: Vec<State> = Vec::new();
        let mut state_index = std::collections::HashMap::with_capacity(def.states.len());
        for s in &def.states {
            let what = format!("state '{}'", s.name);
            if state_index.insert(s.name.as_str(), states.len()).is_some() {
                return Err(Error::InvalidParameter(format!(
                    "two states are named '{}'",
                    s.name
                )));
            }
            let motion = match (&s.clip, &s.blend_space) {
                (Some(c), None) => Motion::Clip {
                    clip: clip(c, &what)?,
                    looping: s.looping,
                },
                (None, Some(b)) => {
                    let param = params
                        .iter()
                        .position(|p| p.0 == b.parameter && p.1 == ParamKind::Float)
                        .ok_or_else(|| {
                            Error::InvalidParameter(format!(
                                "{what}: no float parameter '{}'",
                                b.parameter
                            ))
                        })?;
                    let mut points = Vec::new();
                    for (x, c) in &b.clips {
                        points.push((*x, clip(c, &what)?));
                    }
                    let space = BlendSpace1D { points };
                    space
                        .validate()
                        .map_err(|e| Error::InvalidParameter(format!("{what}: {e}")))?;
                    Motion::Space { space, param }
                }
                _ => {
                    return Err(Error::InvalidParameter(format!(
                        "{what}: give exactly one of `clip` and `blend_space`"
                    )))
                }
            };
            if !(s.speed.is_finite() && s.speed >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "{what}: speed must be finite and ≥ 0"
                )));
            }
            states.push(State {
                name: s.name.clone(),
                motion,
                speed: s.speed,
            });
        }
        if states.is_empty() {
            return Err(Error::InvalidParameter(
                "state machine has no states".into(),
            ));
        }
        let state = |name: &str, what: &str| {
            state_index
                .get(name)
                .copied()
                .ok_or_else(|| Error::InvalidParameter(format!("{what}: no state named '{name}'")))
        };
        let mut transitions = Vec::new();
        for (i, t) in def.transitions.iter().enumerate() {
            let what = format!("transition {} ({} → {})", i + 1, t.from, t.to);
            let from = if t.from == "*" {
                None
            } else {
                Some(state(&t.from, &what)?)
            };
            let to = state(&t.to, &what)?;
            if !(t.fade.is_finite() && t.fade >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "{what}: fade must be finite and ≥ 0"
                )));
            }
            let conds = t
                .when
                .iter()
                .map(|c| parse_cond(c, &params, &what))
                .collect::<Result<Vec<_>>>()?;
            transitions.push(Transition {
                from,
                to,
                conds,
                fade: t.fade,
                events: t.events.clone(),
            });
        }
        let initial = match &def.initial {
            Some(n) => state(n, "initial")?,
            None => 0,
        };
        if durations.len() != clip_names.len()
            || durations.iter().any(|d| !(d.is_finite() && *d >= 0.0))
        {
            return Err(Error::InvalidParameter(
                "clip durations must be finite, ≥ 0, one per clip".into(),
            ));
        }
        Ok(Self {
            params,
            states,
            transitions,
            initial,
            durations: durations.to_vec(),
        })
    }

    /// A fresh per-character state at the initial state with default parameters.
    pub fn new_state(&self) -> StateMachineState {
        StateMachineState {
            current: Playing {
                state: self.initial,
                time: 0.0,
                phase: BlendSpacePhase::default(),
            },
            fading: None,
            values: self.params.iter().map(|p| p.2).collect(),
            weights: Vec::with_capacity(8),
        }
    }

    /// Index of the parameter called `name`.
    pub fn param(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.0 == name)
    }

    /// Index of the state called `name`.
    pub fn state(&self, name: &str) -> Option<usize> {
        self.states.iter().position(|s| s.name == name)
    }

    /// Name of state `i`.
    pub fn state_name(&self, i: usize) -> &str {
        &self.states[i].name
    }

    /// Number of states.
    pub fn state_count(&self) -> usize {
        self.states.len()
    }

    fn advance(&self, p: &mut Playing, values: &[f32], dt: f32, scratch: &mut Vec<f32>) {
        let s = &self.states[p.state];
        let dt = dt * s.speed;
        p.time += dt;
        if let Motion::Space { space, param } = &s.motion {
            scratch.resize(space.points.len(), 0.0);
            space.advance(&mut p.phase, values[*param], dt, &self.durations, scratch);
        }
    }

    fn finished(&self, p: &Playing) -> bool {
        match self.states[p.state].motion {
            Motion::Clip {
                clip,
                looping: false,
            } => p.time >= self.durations[clip],
            _ => false,
        }
    }

    fn push_layers(
        &self,
        p: &Playing,
        weight: f32,
        values: &[f32],
        plan: &mut BlendPlan,
        scratch: &mut Vec<f32>,
    ) {
        if weight <= 0.0 {
            return;
        }
        let state = &self.states[p.state];
        match &state.motion {
            Motion::Clip { clip, looping } => {
                let d = self.durations[*clip];
                let time = if *looping && d > 0.0 {
                    p.time.rem_euclid(d)
                } else {
                    p.time.clamp(0.0, d)
                };
                let rate = if !*looping && p.time >= d {
                    0.0
                } else {
                    state.speed
                };
                plan.layers.push(PlanLayer {
                    clip: *clip,
                    time,
                    weight,
                    rate,
                    looping: *looping,
                });
            }
            Motion::Space { space, param } => {
                scratch.resize(space.points.len(), 0.0);
                space.weights(values[*param], scratch);
                let cycle: f32 = space
                    .points
                    .iter()
                    .zip(scratch.iter())
                    .map(|(pt, w)| w * self.durations[pt.1])
                    .sum();
                for (pt, &w) in space.points.iter().zip(scratch.iter()) {
                    if w > 0.0 {
                        let d = self.durations[pt.1];
                        let time = p.phase.phase * d;
                        let rate = if cycle > 1e-6 {
                            state.speed * d / cycle
                        } else {
                            0.0
                        };
                        plan.layers.push(PlanLayer {
                            clip: pt.1,
                            time,
                            weight: weight * w,
                            rate,
                            looping: true,
                        });
                    }
                }
            }
        }
    }

    /// Advances `st` by `dt` seconds, fires at most one transition, and writes what to play
    /// into `plan` (cleared first; its buffers are reused, so steady play allocates nothing).
    pub fn update(&self, st: &mut StateMachineState, dt: f32, plan: &mut BlendPlan) {
        let dt = if dt.is_finite() { dt.max(0.0) } else { 0.0 };
        let StateMachineState {
            current,
            fading,
            values,
            weights,
        } = st;
        plan.layers.clear();
        plan.events.clear();
        plan.transitioned = false;
        self.advance(current, values, dt, weights);
        if let Some((mut p, elapsed, duration)) = *fading {
            self.advance(&mut p, values, dt, weights);
            let elapsed = elapsed + dt;
            *fading = (elapsed + 1e-5 < duration).then_some((p, elapsed, duration));
        }
        let finished = self.finished(current);
        let fired = self.transitions.iter().find(|t| {
            t.from.is_none_or(|f| f == current.state)
                && t.to != current.state
                && t.conds.iter().all(|c| match *c {
                    Cond::ClipFinished => finished,
                    Cond::Flag { param, value } => (values[param] != 0.0) == value,
                    Cond::Compare { param, op, value } => {
                        let v = values[param];
                        match op {
                            Op::Lt => v < value,
                            Op::Le => v <= value,
                            Op::Gt => v > value,
                            Op::Ge => v >= value,
                            Op::Eq => v == value,
                            Op::Ne => v != value,
                        }
                    }
                })
        });
        if let Some(t) = fired {
            for c in &t.conds {
                if let Cond::Flag { param, value: true } = *c {
                    if self.params[param].1 == ParamKind::Trigger {
                        values[param] = 0.0;
                    }
                }
            }
            plan.events.extend(t.events.iter().cloned());
            plan.transitioned = true;
            *fading = (t.fade > 0.0).then_some((*current, 0.0, t.fade));
            *current = Playing {
                state: t.to,
                time: 0.0,
                phase: BlendSpacePhase::default(),
            };
        }
        let w_new = match *fading {
            Some((_, elapsed, duration)) => (elapsed / duration).clamp(0.0, 1.0),
            None => 1.0,
        };
        self.push_layers(current, w_new, values, plan, weights);
        if let Some((p, _, _)) = *fading {
            self.push_layers(&p, 1.0 - w_new, values, plan, weights);
        }
        plan.state = current.state;
    }
}
