//! Timed settings overrides (KawaiiPhysics' `StartPhysicsSettingsOverride`, its master
//! branch after 1.21): scales of a chain's damping, stiffness, world damping, radius and
//! limit angle that blend in, hold and blend out over a set time, up to
//! [`MAX_OVERRIDES`] at once, multiplying.
//!
//! An override is a request (its scales, its envelope, the chains it acts on) taken in at
//! the start of the next frame. Each frame its elapsed time first advances by the frame's
//! time, then the new requests join at elapsed 0 (they start at alpha 0: their rise begins
//! with this frame), then stops are taken in (the alpha they were at folded into the peak,
//! then a decay of their blend-out), then the ended ones leave, then the oldest leave
//! while more than [`MAX_OVERRIDES`] remain: KawaiiPhysics'
//! `ConsumeAndAdvancePhysicsSettingsOverrides`. A chain's scale of a setting is the product
//! over the overrides on it of `lerp(1, scale, peak · envelope(elapsed))`, and the point's
//! value is KawaiiPhysics' `clamp(base · curve · scale)`; a limit angle above 0 never falls
//! below 1e-4° (0 means no limit).
//!
//! When the scales take effect: `classic` and `kawaii` once a frame, at the frame's end (as
//! KawaiiPhysics evaluates them before its substeps). `fixed` keeps a clock of its own, so
//! that an override's look does not depend on the frame rate: a request or a stop made
//! between two frames happens at that moment (its clock starts there, not at the next
//! frame's end as KawaiiPhysics' does), and each step reads the scales at its own time,
//! the output step at the frame's end.

use super::compile::ChainRig;
use super::settings::ChainSettings;
use crate::error::{Error, Result};

/// At most this many overrides act at once; a newer one drops the oldest (KawaiiPhysics'
/// `MaxPhysicsSettingsOverrides`).
pub const MAX_OVERRIDES: usize = 8;

/// KawaiiPhysics' `KINDA_SMALL_NUMBER`: envelope phases shorter than this are none.
const KINDA_SMALL: f32 = 1e-4;

/// Multipliers of a chain's physics settings (KawaiiPhysics' `FKawaiiPhysicsSettingsScale`):
/// all 1 changes nothing. The world dampings are "how much of the character's motion is
/// ignored", so a scale under 1 makes the chain swing more; a radius scale of 0 turns
/// collision off; a limit angle stays unlimited when its base is 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SettingsScale {
    /// Scales `damping`.
    pub damping: f32,
    /// Scales `stiffness`.
    pub stiffness: f32,
    /// Scales `world_damping_location`.
    pub world_damping_location: f32,
    /// Scales `world_damping_rotation`.
    pub world_damping_rotation: f32,
    /// Scales `radius`.
    pub radius: f32,
    /// Scales `limit_angle`.
    pub limit_angle: f32,
}

impl Default for SettingsScale {
    fn default() -> Self {
        Self::ONE
    }
}

impl SettingsScale {
    /// Every scale 1: no change.
    pub const ONE: Self = Self {
        damping: 1.0,
        stiffness: 1.0,
        world_damping_location: 1.0,
        world_damping_rotation: 1.0,
        radius: 1.0,
        limit_angle: 1.0,
    };

    /// The scales by their rig-file names, in this order: `damping`, `stiffness`,
    /// `world_damping_location`, `world_damping_rotation`, `radius`, `limit_angle`.
    pub const NAMES: [&'static str; 6] = [
        "damping",
        "stiffness",
        "world_damping_location",
        "world_damping_rotation",
        "radius",
        "limit_angle",
    ];

    /// The six scales in [`SettingsScale::NAMES`]' order.
    pub fn to_array(self) -> [f32; 6] {
        [
            self.damping,
            self.stiffness,
            self.world_damping_location,
            self.world_damping_rotation,
            self.radius,
            self.limit_angle,
        ]
    }

    /// The scales from six values in [`SettingsScale::NAMES`]' order.
    pub fn from_array(a: [f32; 6]) -> Self {
        Self {
            damping: a[0],
            stiffness: a[1],
            world_damping_location: a[2],
            world_damping_rotation: a[3],
            radius: a[4],
            limit_angle: a[5],
        }
    }

    /// Sets the scale named `name` (one of [`SettingsScale::NAMES`]); false for another
    /// name.
    pub fn set(&mut self, name: &str, value: f32) -> bool {
        let mut a = self.to_array();
        match Self::NAMES.iter().position(|n| *n == name) {
            Some(i) => {
                a[i] = value;
                *self = Self::from_array(a);
                true
            }
            None => false,
        }
    }

    /// An error naming the first scale that is negative or not finite.
    pub fn check(&self) -> Result<()> {
        for (name, v) in Self::NAMES.iter().zip(self.to_array()) {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "settings override: the {name} scale {v} is not a number ≥ 0"
                )));
            }
        }
        Ok(())
    }

    fn is_one(&self) -> bool {
        *self == Self::ONE
    }
}

/// When an override acts: `duration` seconds in all (`f32::INFINITY`: until it is
/// stopped), of which it blends in over the first `blend_in` and out over the last
/// `blend_out`; where the two blends are longer than the duration, both are shortened in
/// proportion and nothing is held (KawaiiPhysics' `ResolveWindBlowEnvelope`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverrideTiming {
    /// Seconds in all, blends included; > 0, or infinite.
    pub duration: f32,
    /// Seconds to blend in from no change to the full scales.
    pub blend_in: f32,
    /// Seconds to blend out at the end.
    pub blend_out: f32,
}

impl Default for OverrideTiming {
    /// KawaiiPhysics' defaults: 2 s, 0.2 s in, 0.5 s out.
    fn default() -> Self {
        Self {
            duration: 2.0,
            blend_in: 0.2,
            blend_out: 0.5,
        }
    }
}

impl OverrideTiming {
    /// An error naming a duration that is not > 0 or a blend that is negative or not
    /// finite.
    pub fn check(&self) -> Result<()> {
        if self.duration.is_nan() || self.duration <= 0.0 {
            return Err(Error::InvalidParameter(format!(
                "settings override: the duration {} s is not > 0",
                self.duration
            )));
        }
        for (name, v) in [("blend_in", self.blend_in), ("blend_out", self.blend_out)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidParameter(format!(
                    "settings override: {name} {v} s is not a time ≥ 0"
                )));
            }
        }
        Ok(())
    }

    /// Rise, hold and decay (KawaiiPhysics' `ResolveWindBlowEnvelope`).
    fn envelope(&self) -> (f32, f32, f32) {
        let (rise, decay) = (self.blend_in.max(0.0), self.blend_out.max(0.0));
        let edge = rise + decay;
        if edge > self.duration && edge > 0.0 {
            let s = self.duration / edge;
            (rise * s, 0.0, decay * s)
        } else {
            (rise, (self.duration - edge).max(0.0), decay)
        }
    }
}

/// How far an envelope of `rise`, `hold` and `decay` seconds is in at `elapsed`: 0 → 1
/// linearly over the rise, 1 over the hold, 1 → 0 over the decay, 0 before and after
/// (KawaiiPhysics' `EvaluateEnvelopeAlpha01`).
pub fn envelope_alpha(rise: f32, hold: f32, decay: f32, elapsed: f32) -> f32 {
    if elapsed < 0.0 || elapsed.is_nan() {
        return 0.0;
    }
    let (rise, hold, decay) = (rise.max(0.0), hold.max(0.0), decay.max(0.0));
    if rise > KINDA_SMALL && elapsed < rise {
        return elapsed / rise;
    }
    if elapsed < rise + hold {
        return 1.0;
    }
    if decay <= KINDA_SMALL {
        return 0.0;
    }
    let into = elapsed - rise - hold;
    if into < decay {
        1.0 - into / decay
    } else {
        0.0
    }
}

/// A handle to an override, to stop it early ([`crate::CharacterSim::stop_settings_override`]).
/// Handles are never 0, fit an `i32`, and are not given again by the same character
/// until 2³¹ − 1 more overrides have started.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct OverrideHandle(pub u32);

/// An envelope's state: its phases, where it is, and the peak a stop folded in.
#[derive(Debug, Clone, Copy)]
struct Clock {
    rise: f32,
    hold: f32,
    decay: f32,
    elapsed: f32,
    peak: f32,
}

impl Clock {
    fn alpha(&self, back: f32) -> f32 {
        self.peak * envelope_alpha(self.rise, self.hold, self.decay, self.elapsed - back)
    }

    /// A stop: the alpha now folded into the peak, then a decay of `blend_out`.
    fn stop(&mut self, blend_out: f32) {
        self.peak *= envelope_alpha(self.rise, self.hold, self.decay, self.elapsed);
        self.rise = 0.0;
        self.hold = 0.0;
        self.decay = blend_out;
        self.elapsed = 0.0;
    }

    fn ended(&self) -> bool {
        self.elapsed >= self.rise + self.hold + self.decay
    }
}

#[derive(Debug, Clone)]
struct Item {
    handle: u32,
    name: Option<Box<str>>,
    /// The chains it acts on (`None`: all).
    chains: Option<Box<[u16]>>,
    scale: SettingsScale,
    /// KawaiiPhysics' clock (`classic`, `kawaii`): its elapsed time is at the frame's end,
    /// 0 in the frame that takes it in; a stop takes effect at the frame's end.
    kp: Clock,
    /// `fixed` mode's clock: time since the request, which (as a stop) happened between
    /// frames; its elapsed time is at the frame's end.
    fixed: Clock,
}

impl Item {
    fn on(&self, ci: usize) -> bool {
        self.chains
            .as_deref()
            .is_none_or(|c| c.contains(&(ci as u16)))
    }
}

/// A character's overrides: those acting, and the requests and stops taken in at the
/// next frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct Overrides {
    items: Vec<Item>,
    pending: Vec<Item>,
    stops: Vec<(u32, f32)>,
    next: u32,
}

impl Overrides {
    /// Queues an override; the oldest request not yet taken in is dropped past
    /// [`MAX_OVERRIDES`]. A named one stops the acting or queued ones of that name,
    /// blending them out over its own blend-in (a cross-fade).
    pub(crate) fn start(
        &mut self,
        scale: SettingsScale,
        timing: OverrideTiming,
        chains: Option<Box<[u16]>>,
        name: Option<&str>,
    ) -> Result<OverrideHandle> {
        scale.check()?;
        timing.check()?;
        if let Some(name) = name {
            let old: Vec<u32> = self
                .items
                .iter()
                .chain(&self.pending)
                .filter(|i| i.name.as_deref() == Some(name))
                .map(|i| i.handle)
                .collect();
            for h in old {
                self.stop(OverrideHandle(h), timing.blend_in);
            }
        }
        // Handles fit a C `int32_t` (1..=i32::MAX, then round again).
        self.next = if self.next >= i32::MAX as u32 {
            1
        } else {
            self.next + 1
        };
        let (rise, hold, decay) = timing.envelope();
        if self.pending.len() >= MAX_OVERRIDES {
            self.pending.remove(0);
        }
        let clock = Clock {
            rise,
            hold,
            decay,
            elapsed: 0.0,
            peak: 1.0,
        };
        self.pending.push(Item {
            handle: self.next,
            name: name.map(Into::into),
            chains,
            scale,
            kp: clock,
            fixed: clock,
        });
        Ok(OverrideHandle(self.next))
    }

    /// Queues a stop: the override blends out from where it is over `blend_out` seconds
    /// (0: at once). A second stop of the same handle before the next frame replaces the
    /// first's time. False when no override acting or queued has the handle.
    pub(crate) fn stop(&mut self, handle: OverrideHandle, blend_out: f32) -> bool {
        let h = handle.0;
        if !self
            .items
            .iter()
            .chain(&self.pending)
            .any(|i| i.handle == h)
        {
            return false;
        }
        let blend_out = if blend_out.is_finite() {
            blend_out.max(0.0)
        } else {
            0.0
        };
        if let Some(s) = self.stops.iter_mut().find(|s| s.0 == h) {
            s.1 = blend_out;
            return true;
        }
        if self.stops.len() >= MAX_OVERRIDES {
            self.stops.remove(0);
        }
        self.stops.push((h, blend_out));
        true
    }

    /// Queues stops of every override named `name`; how many.
    pub(crate) fn stop_named(&mut self, name: &str, blend_out: f32) -> usize {
        let hs: Vec<u32> = self
            .items
            .iter()
            .chain(&self.pending)
            .filter(|i| i.name.as_deref() == Some(name))
            .map(|i| i.handle)
            .collect();
        hs.iter()
            .filter(|&&h| self.stop(OverrideHandle(h), blend_out))
            .count()
    }

    /// Drops every override, acting and queued (a rig change, a clear).
    pub(crate) fn clear(&mut self) {
        self.items.clear();
        self.pending.clear();
        self.stops.clear();
    }

    /// The frame's bookkeeping (see the module's notes) for a frame of `dt`; true while
    /// any acts.
    pub(crate) fn advance(&mut self, dt: f32) -> bool {
        if self.items.is_empty() && self.pending.is_empty() {
            self.stops.clear();
            return false;
        }
        for item in &mut self.items {
            item.kp.elapsed += dt;
        }
        self.items.append(&mut self.pending);
        for (h, blend_out) in std::mem::take(&mut self.stops) {
            if blend_out <= KINDA_SMALL {
                self.items.retain(|i| i.handle != h);
                continue;
            }
            for item in self.items.iter_mut().filter(|i| i.handle == h) {
                item.kp.stop(blend_out);
                item.fixed.stop(blend_out);
            }
        }
        // The fixed clock's requests and stops were at the frame's start.
        for item in &mut self.items {
            item.fixed.elapsed += dt;
        }
        self.items.retain(|i| !(i.kp.ended() && i.fixed.ended()));
        while self.items.len() > MAX_OVERRIDES {
            self.items.remove(0);
        }
        !self.items.is_empty()
    }

    /// Whether any override acts this frame.
    pub(crate) fn active(&self) -> bool {
        !self.items.is_empty()
    }

    /// How many act this frame.
    pub(crate) fn len(&self) -> usize {
        self.items.len()
    }

    /// Chain `ci`'s scales `back` seconds before the frame's end, on `fixed` mode's clock
    /// or KawaiiPhysics' (`ComputeEffectivePhysicsSettingsOverrideScale`).
    pub(crate) fn scale(&self, ci: usize, back: f32, fixed: bool) -> SettingsScale {
        let mut e = SettingsScale::ONE;
        for item in self.items.iter().filter(|i| i.on(ci)) {
            let a = if fixed {
                item.fixed.alpha(back)
            } else {
                item.kp.alpha(back)
            };
            let s = &item.scale;
            let lerp = |to: f32| 1.0 + (to - 1.0) * a;
            e.damping *= lerp(s.damping);
            e.stiffness *= lerp(s.stiffness);
            e.world_damping_location *= lerp(s.world_damping_location);
            e.world_damping_rotation *= lerp(s.world_damping_rotation);
            e.radius *= lerp(s.radius);
            e.limit_angle *= lerp(s.limit_angle);
        }
        e
    }
}

/// The per-point settings a step reads: the rig's, or (while overrides act) the scaled
/// copies; and per chain the radius scale (bridge points, the world's broad phase).
#[derive(Clone, Copy)]
pub(crate) struct Params<'a> {
    pub damping: &'a [f32],
    pub stiffness: &'a [f32],
    pub radius: &'a [f32],
    pub wd_location: &'a [f32],
    pub wd_rotation: &'a [f32],
    pub limit_angle: &'a [f32],
    pub radius_scale: &'a [f32],
}

/// The scaled copies of the per-point settings ([`Params`]), written chain by chain.
#[derive(Debug, Clone, Default)]
pub(crate) struct ScaledParams {
    /// Whether the steps read the copies (some override acts).
    pub active: bool,
    damping: Vec<f32>,
    stiffness: Vec<f32>,
    radius: Vec<f32>,
    wd_location: Vec<f32>,
    wd_rotation: Vec<f32>,
    limit_angle: Vec<f32>,
    /// Per chain (all 1 while none acts).
    radius_scale: Vec<f32>,
}

impl ScaledParams {
    pub(crate) fn new(rig: &ChainRig) -> Self {
        Self {
            radius_scale: vec![1.0; rig.chains.len()],
            ..Self::default()
        }
    }

    /// Chain `ci`'s radius scale now (1 while no override acts).
    pub(crate) fn radius_scale(&self, ci: usize) -> f32 {
        self.radius_scale[ci]
    }

    /// What the steps read.
    pub(crate) fn view<'a>(&'a self, rig: &'a ChainRig) -> Params<'a> {
        if self.active {
            Params {
                damping: &self.damping,
                stiffness: &self.stiffness,
                radius: &self.radius,
                wd_location: &self.wd_location,
                wd_rotation: &self.wd_rotation,
                limit_angle: &self.limit_angle,
                radius_scale: &self.radius_scale,
            }
        } else {
            Params {
                damping: &rig.damping,
                stiffness: &rig.stiffness,
                radius: &rig.radius,
                wd_location: &rig.wd_location,
                wd_rotation: &rig.wd_rotation,
                limit_angle: &rig.limit_angle,
                radius_scale: &self.radius_scale,
            }
        }
    }

    /// Turns the copies on (`active`, every chain's written at its unscaled values first)
    /// or off.
    pub(crate) fn set_active(&mut self, rig: &ChainRig, active: bool) {
        if active && !self.active {
            self.damping.clone_from(&rig.damping);
            self.stiffness.clone_from(&rig.stiffness);
            self.radius.clone_from(&rig.radius);
            self.wd_location.clone_from(&rig.wd_location);
            self.wd_rotation.clone_from(&rig.wd_rotation);
            self.limit_angle.clone_from(&rig.limit_angle);
        }
        if !active {
            self.radius_scale.fill(1.0);
        }
        self.active = active;
    }

    /// Writes chain `ci`'s points at `scale`: KawaiiPhysics'
    /// `UpdatePhysicsSettingsOfModifyBones`, the base value times the curve at the point's
    /// length rate times the scale, clamped as the rig clamps it.
    pub(crate) fn write(&mut self, rig: &ChainRig, ci: usize, scale: &SettingsScale) {
        let chain = &rig.chains[ci];
        let points = chain.points.clone();
        self.radius_scale[ci] = scale.radius;
        if scale.is_one() {
            for (dst, src) in [
                (&mut self.damping, &rig.damping),
                (&mut self.stiffness, &rig.stiffness),
                (&mut self.radius, &rig.radius),
                (&mut self.wd_location, &rig.wd_location),
                (&mut self.wd_rotation, &rig.wd_rotation),
                (&mut self.limit_angle, &rig.limit_angle),
            ] {
                dst[points.clone()].copy_from_slice(&src[points.clone()]);
            }
            return;
        }
        for p in points {
            let v = point_settings(&chain.settings, rig.length_rate[p], scale);
            self.damping[p] = v[0];
            self.stiffness[p] = v[1];
            self.wd_location[p] = v[2];
            self.wd_rotation[p] = v[3];
            self.radius[p] = v[4];
            self.limit_angle[p] = v[5];
        }
    }
}

/// A point's damping, stiffness, world dampings, radius and limit angle (radians) at
/// length rate `x` under `scale`, as the rig compiles them with every scale 1.
pub(crate) fn point_settings(s: &ChainSettings, x: f32, scale: &SettingsScale) -> [f32; 6] {
    let c = &s.curves;
    let unit = |v: f32| v.clamp(0.0, 1.0);
    let base_limit = (s.limit_angle * c.limit_angle.eval(x)).max(0.0);
    let limit = if base_limit > 0.0 && scale.limit_angle != 1.0 {
        (base_limit * scale.limit_angle).max(KINDA_SMALL)
    } else {
        base_limit
    };
    [
        unit(s.damping * c.damping.eval(x) * scale.damping),
        unit(s.stiffness * c.stiffness.eval(x) * scale.stiffness),
        unit(
            s.world_damping_location
                * c.world_damping_location.eval(x)
                * scale.world_damping_location,
        ),
        unit(
            s.world_damping_rotation
                * c.world_damping_rotation.eval(x)
                * scale.world_damping_rotation,
        ),
        (s.radius * c.radius.eval(x) * scale.radius).max(0.0),
        limit.clamp(0.0, 180.0).to_radians(),
    ]
}
