//! A character's secondary motion steered at run time: external forces set, changed and
//! cleared, chain alphas, and the animation events that do the same from a state
//! machine's transitions (KawaiiPhysics' anim notifies).

use super::CharacterSim;
use crate::dynamics::chain::{
    CustomForce, ExternalForceSettings, GustRequest, OverrideHandle, OverrideTiming, SettingsScale,
};
use crate::error::{Error, Result};
use std::sync::Arc;

/// The prefix of the animation events [`CharacterSim::apply_event`] acts on.
pub const EVENT_PREFIX: &str = "tassel:";

impl CharacterSim {
    /// Adds an external force to the chains, or replaces the one of the same name (its
    /// clock starts again): the rig file's `[[external_force]]` at run time. Errors name
    /// the force and the entry; the forces are unchanged then.
    pub fn set_external_force(&mut self, settings: &ExternalForceSettings) -> Result<()> {
        let rig = Arc::clone(&self.rig);
        self.state
            .set_external_force(&rig.skeleton, &rig.chains, settings)
    }

    /// Adds (or replaces by name) a force written in Rust (see [`CustomForce`]):
    /// `settings` give its name, chains, bone filters, space, rate curve and random scale.
    pub fn set_custom_force(
        &mut self,
        settings: &ExternalForceSettings,
        force: Arc<dyn CustomForce>,
    ) -> Result<()> {
        let rig = Arc::clone(&self.rig);
        self.state
            .set_custom_force(&rig.skeleton, &rig.chains, settings, force)
    }

    /// Turns the named external force on or off; an error names a force that does not
    /// exist.
    pub fn enable_external_force(&mut self, name: &str, on: bool) -> Result<()> {
        if self.state.enable_external_force(name, on) {
            Ok(())
        } else {
            Err(no_force(name))
        }
    }

    /// Applies the named external force for one step of each chain it reaches, whether
    /// it is on or off (a one-shot push: an explosion, a landing).
    pub fn external_force_once(&mut self, name: &str) -> Result<()> {
        let rig = Arc::clone(&self.rig);
        if self.state.external_force_once(&rig.chains, name) {
            Ok(())
        } else {
            Err(no_force(name))
        }
    }

    /// Removes the named external force; false when there was none.
    pub fn remove_external_force(&mut self, name: &str) -> bool {
        self.state.remove_external_force(name)
    }

    /// Removes every external force, the rig file's included.
    pub fn clear_external_forces(&mut self) {
        self.state.clear_external_forces()
    }

    /// The external forces' names, each with whether it is on.
    pub fn external_forces(&self) -> impl Iterator<Item = (&str, bool)> + '_ {
        self.state.external_forces()
    }

    /// Sets the run-time alpha (0..=1, multiplying each chain's `alpha`) of the named
    /// chain, or of every chain with `None`: 0 shows the animated pose, 1 the simulated
    /// one; the chains keep simulating underneath.
    pub fn set_chain_alpha(&mut self, chain: Option<&str>, alpha: f32) -> Result<()> {
        let chains = &self.rig.chains;
        let range = match chain {
            Some(name) => {
                let ci = self.rig.chain_index(name).ok_or_else(|| {
                    Error::InvalidParameter(format!("there is no chain named '{name}'"))
                })?;
                ci..ci + 1
            }
            None => 0..chains.chain_count(),
        };
        if !(0.0..=1.0).contains(&alpha) {
            return Err(Error::InvalidParameter(format!(
                "alpha {alpha} is outside 0..=1"
            )));
        }
        for ci in range {
            self.state.set_alpha(ci, alpha)?;
        }
        Ok(())
    }

    /// Starts a gust of the procedural wind named `name` (KawaiiPhysics'
    /// `TriggerProceduralWindGust`): its strength rises, holds and decays on the wind's
    /// clock and adds to the wind's total; gusts stack. Errors name a bad gust, or a force
    /// that does not exist or is not a procedural wind.
    pub fn trigger_wind_gust(&mut self, name: &str, gust: GustRequest) -> Result<()> {
        self.state.trigger_wind_gust(name, gust)
    }

    /// Fades every gust of the procedural wind `name` out over `blend_out` seconds (0: at
    /// once).
    pub fn stop_wind_gusts(&mut self, name: &str, blend_out: f32) -> Result<()> {
        self.state.stop_wind_gusts(name, blend_out)
    }

    /// Starts a timed settings override of the chains (KawaiiPhysics'
    /// `StartPhysicsSettingsOverride`): `scale` multiplies the damping, stiffness, world
    /// dampings, radius and limit angle of the chain named `chain` (`None`: every chain),
    /// blending in and out over `timing`, from the next frame; up to
    /// [`MAX_OVERRIDES`](crate::dynamics::chain::MAX_OVERRIDES) act at once and they
    /// multiply. `name` (optional) lets [`stop_named_settings_override`] and the
    /// `tassel:stop_override` event stop it; starting a name again cross-fades. Errors name
    /// a bad scale, time or chain, or say that the character has no chains.
    ///
    /// [`stop_named_settings_override`]: Self::stop_named_settings_override
    ///
    /// ```
    /// use tassel::dynamics::chain::{OverrideTiming, SettingsScale};
    /// use tassel::{builtin, CharacterSim};
    /// let c = builtin::character();
    /// let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    /// // Loose hair for two seconds: half the stiffness, blending in over 0.2 s.
    /// let scale = SettingsScale { stiffness: 0.5, ..SettingsScale::ONE };
    /// let h = sim
    ///     .start_settings_override(scale, OverrideTiming::default(), None, None)
    ///     .unwrap();
    /// assert!(sim.stop_settings_override(h, 0.5));
    /// ```
    pub fn start_settings_override(
        &mut self,
        scale: SettingsScale,
        timing: OverrideTiming,
        chain: Option<&str>,
        name: Option<&str>,
    ) -> Result<OverrideHandle> {
        let rig = Arc::clone(&self.rig);
        if rig.chains.chain_count() == 0 {
            return Err(Error::InvalidParameter(
                "settings override: the character has no chains for it to act on".into(),
            ));
        }
        let one;
        let chains = match chain {
            Some(c) => {
                one = [rig.chain_index(c).ok_or_else(|| {
                    Error::InvalidParameter(format!(
                        "settings override: there is no chain named '{c}'"
                    ))
                })?];
                Some(&one[..])
            }
            None => None,
        };
        self.state
            .start_settings_override(&rig.chains, scale, timing, chains, name)
    }

    /// Stops a settings override: it blends out from where it is over `blend_out` seconds
    /// (0: at once). False when no override has that handle (it has ended).
    pub fn stop_settings_override(&mut self, handle: OverrideHandle, blend_out: f32) -> bool {
        self.state.stop_settings_override(handle, blend_out)
    }

    /// Stops every settings override started with `name`; how many.
    pub fn stop_named_settings_override(&mut self, name: &str, blend_out: f32) -> usize {
        self.state.stop_named_settings_override(name, blend_out)
    }

    /// The settings scales of the chain named `chain` as the last frame ended (all 1 while
    /// no override acts on it); `None` for a chain that does not exist.
    pub fn settings_scale(&self, chain: &str) -> Option<SettingsScale> {
        let ci = self.rig.chain_index(chain)?;
        Some(self.state.settings_scale(&self.rig.chains, ci))
    }

    /// Acts on one animation event (a state machine transition's `events` entry, see
    /// [`crate::anim::BlendPlan::events`]) that starts with `tassel:`, as KawaiiPhysics'
    /// anim notifies do:
    ///
    /// | event | does |
    /// |---|---|
    /// | `tassel:reset_dynamics` | [`reset`](Self::reset): the next frame starts from the pose |
    /// | `tassel:set_alpha 0.3` | [`set_chain_alpha`](Self::set_chain_alpha) of every chain |
    /// | `tassel:set_alpha 0.3 hair` | the same for chain `hair` |
    /// | `tassel:enable_force gust` | [`enable_external_force`](Self::enable_external_force) |
    /// | `tassel:disable_force gust` | turns it off |
    /// | `tassel:force_once gust` | [`external_force_once`](Self::external_force_once) |
    /// | `tassel:override slowmo stiffness=0.5 damping=2 duration=2 blend_in=0.2 blend_out=0.5 chain=hair` | [`start_settings_override`](Self::start_settings_override) named `slowmo`: any of the six scales (`damping`, `stiffness`, `world_damping_location`, `world_damping_rotation`, `radius`, `limit_angle`; unset: 1), the times (KawaiiPhysics' 2, 0.2 and 0.5 s when unset; `duration=inf`: until stopped), the chain (unset: every chain) |
    /// | `tassel:gust breeze strength=3 rise=0.2 hold=0.5 decay=1` | [`trigger_wind_gust`](Self::trigger_wind_gust) of the procedural wind `breeze` (unset times: 0) |
    /// | `tassel:stop_gust breeze 0.3` | [`stop_wind_gusts`](Self::stop_wind_gusts) over 0.3 s (unset: 0.5 s) |
    /// | `tassel:stop_override slowmo 0.3` | [`stop_named_settings_override`](Self::stop_named_settings_override), blending out over 0.3 s (unset: 0.5 s) |
    ///
    /// Returns `Ok(false)` for an event that does not start with `tassel:` (the game's
    /// own), `Ok(true)` when it acted, and an error naming the event when it starts with
    /// `tassel:` but is not one of these or names what does not exist.
    ///
    /// ```
    /// use tassel::{builtin, CharacterSim};
    /// let c = builtin::character();
    /// let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
    /// assert!(sim.apply_event("tassel:set_alpha 0.5").unwrap());
    /// assert!(!sim.apply_event("footstep").unwrap());
    /// assert!(sim.apply_event("tassel:enable_force nothing").is_err());
    /// ```
    pub fn apply_event(&mut self, event: &str) -> Result<bool> {
        let Some(rest) = event.strip_prefix(EVENT_PREFIX) else {
            return Ok(false);
        };
        let bad = |why: String| Error::InvalidParameter(format!("event '{event}': {why}"));
        let mut words = rest.split_whitespace();
        let verb = words.next().unwrap_or("");
        let args: Vec<&str> = words.collect();
        let one = |args: &[&str]| match args {
            [name] => Ok(name.to_string()),
            _ => Err(bad("takes one force name".into())),
        };
        match verb {
            "reset_dynamics" if args.is_empty() => self.reset(),
            "set_alpha" => {
                let (value, chain) = match args.as_slice() {
                    [v] => (v, None),
                    [v, chain] => (v, Some(*chain)),
                    _ => return Err(bad("takes an alpha and, optionally, a chain name".into())),
                };
                let alpha: f32 = value
                    .parse()
                    .map_err(|_| bad(format!("'{value}' is not a number")))?;
                self.set_chain_alpha(chain, alpha)
                    .map_err(|e| bad(e.to_string()))?;
            }
            "enable_force" | "disable_force" => {
                let name = one(&args)?;
                self.enable_external_force(&name, verb == "enable_force")
                    .map_err(|e| bad(e.to_string()))?;
            }
            "force_once" => {
                let name = one(&args)?;
                self.external_force_once(&name)
                    .map_err(|e| bad(e.to_string()))?;
            }
            "override" => {
                let (name, keys) = args
                    .split_first()
                    .ok_or_else(|| bad("takes a name and key=value pairs".into()))?;
                let mut scale = SettingsScale::ONE;
                let mut timing = OverrideTiming::default();
                let mut chain = None;
                for kv in keys {
                    let (k, v) = kv
                        .split_once('=')
                        .ok_or_else(|| bad(format!("'{kv}' is not key=value")))?;
                    if k == "chain" {
                        chain = Some(v);
                        continue;
                    }
                    let x: f32 = v
                        .parse()
                        .map_err(|_| bad(format!("{k}: '{v}' is not a number")))?;
                    match k {
                        "duration" => timing.duration = x,
                        "blend_in" => timing.blend_in = x,
                        "blend_out" => timing.blend_out = x,
                        _ if scale.set(k, x) => {}
                        _ => {
                            return Err(bad(format!(
                                "'{k}' is not one of {}, duration, blend_in, blend_out, chain",
                                SettingsScale::NAMES.join(", ")
                            )))
                        }
                    }
                }
                self.start_settings_override(scale, timing, chain, Some(name))
                    .map_err(|e| bad(e.to_string()))?;
            }
            "gust" => {
                let (name, keys) = args
                    .split_first()
                    .ok_or_else(|| bad("takes a wind's name and key=value pairs".into()))?;
                let mut gust = GustRequest {
                    strength: 0.0,
                    rise: 0.0,
                    hold: 0.0,
                    decay: 0.0,
                };
                for kv in keys {
                    let (k, v) = kv
                        .split_once('=')
                        .ok_or_else(|| bad(format!("'{kv}' is not key=value")))?;
                    let x: f32 = v
                        .parse()
                        .map_err(|_| bad(format!("{k}: '{v}' is not a number")))?;
                    match k {
                        "strength" => gust.strength = x,
                        "rise" => gust.rise = x,
                        "hold" => gust.hold = x,
                        "decay" => gust.decay = x,
                        _ => {
                            return Err(bad(format!(
                                "'{k}' is not one of strength, rise, hold, decay"
                            )))
                        }
                    }
                }
                self.trigger_wind_gust(name, gust)
                    .map_err(|e| bad(e.to_string()))?;
            }
            "stop_gust" => {
                let (name, blend_out) = match args.as_slice() {
                    [name] => (*name, 0.5),
                    [name, t] => (
                        *name,
                        t.parse::<f32>()
                            .map_err(|_| bad(format!("'{t}' is not a time")))?,
                    ),
                    _ => {
                        return Err(bad(
                            "takes a wind's name and, optionally, a blend-out time".into()
                        ))
                    }
                };
                self.stop_wind_gusts(name, blend_out)
                    .map_err(|e| bad(e.to_string()))?;
            }
            "stop_override" => {
                let (name, blend_out) = match args.as_slice() {
                    [name] => (*name, 0.5),
                    [name, t] => (
                        *name,
                        t.parse::<f32>()
                            .ok()
                            .filter(|t| t.is_finite() && *t >= 0.0)
                            .ok_or_else(|| bad(format!("'{t}' is not a time ≥ 0")))?,
                    ),
                    _ => return Err(bad("takes a name and, optionally, a blend-out time".into())),
                };
                self.stop_named_settings_override(name, blend_out);
            }
            _ => {
                return Err(bad(
                    "not one of reset_dynamics, set_alpha, enable_force, disable_force, \
                     force_once, override, stop_override, gust, stop_gust"
                        .into(),
                ))
            }
        }
        Ok(true)
    }

    /// [`apply_event`](Self::apply_event) for each event in order; stops at the first
    /// error. Returns how many were Tassel's.
    pub fn apply_events<S: AsRef<str>>(&mut self, events: &[S]) -> Result<usize> {
        let mut n = 0;
        for e in events {
            n += usize::from(self.apply_event(e.as_ref())?);
        }
        Ok(n)
    }
}

fn no_force(name: &str) -> Error {
    Error::InvalidParameter(format!("there is no external force named '{name}'"))
}
