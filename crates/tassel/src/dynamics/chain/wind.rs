//! Procedural wind (KawaiiPhysics' `FKawaiiPhysics_ExternalForce_ProceduralWind`, its master
//! branch after 1.21): an external force whose strength is a sum of parts over its own
//! clock — constant, a sway all points share, a ripple that travels from root to tip, a slow
//! strength cycle over those three, seeded smooth noise, and gusts triggered at run time —
//! along a direction that can wander inside a cone:
//!
//! `total = (constant + sway + ripple) × strength_cycle + random + gust`
//!
//! and a point moves by `direction × total × rate × dt` each step, as a `basic` force
//! moves it. Everything is f32, as KawaiiPhysics computes it, and deterministic: the noise
//! is a hash of the seed and the time's grid cell, so the same seed gives the same wind
//! on every run and character.

use crate::error::{Error, Result};
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// KawaiiPhysics' `KINDA_SMALL_NUMBER`.
const SMALL: f32 = 1e-4;
/// The shortest period a part may have, seconds (KawaiiPhysics clamps to it silently).
pub const MIN_PERIOD: f32 = 0.01;
/// The largest strength a part may have.
const MAX_STRENGTH: f32 = 1.0e6;

/// A procedural wind's parts (`[external_force.procedural_wind]`, KawaiiPhysics' names in
/// snake case; angles in degrees, periods in seconds, strengths in the push units of a
/// `basic` force's `force_dir`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ProceduralWindSettings {
    /// The direction the wind blows (normalised on use; zero: +X, KawaiiPhysics' forward).
    pub wind_direction: Vec3,
    /// Half-angle of the cone the direction wanders in (0: it does not).
    pub wind_direction_noise_angle: f32,
    /// How fast the direction wanders: seconds per noise cell.
    pub wind_direction_noise_period: f32,
    /// How fast the wind's own clock runs (0 freezes it).
    pub time_scale: f32,
    /// The steady part.
    pub constant_force: f32,
    /// The amplitude of the sine every point shares.
    pub sway_force: f32,
    /// Its period.
    pub sway_period: f32,
    /// Its phase at time 0.
    pub sway_phase_offset: f32,
    /// The amplitude of the sine that travels from root to tip.
    pub ripple_force: f32,
    /// Its period.
    pub ripple_period: f32,
    /// Its phase at time 0.
    pub ripple_phase_offset: f32,
    /// Its phase lag at the tip (length rate 1): the wave takes `ripple_period ×
    /// delay / 360` to run down the chain; negative runs from tip to root.
    pub ripple_tip_phase_delay: f32,
    /// `[min, max]` of the slow cycle that scales constant + sway + ripple (`[1, 1]`: off).
    pub strength_cycle_range: [f32; 2],
    /// Its period.
    pub strength_cycle_period: f32,
    /// Its phase at time 0.
    pub strength_cycle_phase_offset: f32,
    /// The amplitude of the seeded smooth noise added on top.
    pub random_force: f32,
    /// Seconds per noise cell (shorter: faster jitter).
    pub random_force_period: f32,
}

impl Default for ProceduralWindSettings {
    /// KawaiiPhysics' defaults: no strength in any part.
    fn default() -> Self {
        Self {
            wind_direction: Vec3::X,
            wind_direction_noise_angle: 0.0,
            wind_direction_noise_period: 1.0,
            time_scale: 1.0,
            constant_force: 0.0,
            sway_force: 0.0,
            sway_period: 1.0,
            sway_phase_offset: 0.0,
            ripple_force: 0.0,
            ripple_period: 1.0,
            ripple_phase_offset: 0.0,
            ripple_tip_phase_delay: 180.0,
            strength_cycle_range: [1.0, 1.0],
            strength_cycle_period: 10.0,
            strength_cycle_phase_offset: 0.0,
            random_force: 0.0,
            random_force_period: 0.5,
        }
    }
}

/// The parts of a wind at one time and length rate (KawaiiPhysics' Wind Scope series).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WindSample {
    /// `constant_force`.
    pub constant: f32,
    /// The shared sine.
    pub sway: f32,
    /// The travelling sine at the length rate asked.
    pub ripple: f32,
    /// The slow cycle's multiplier.
    pub strength_cycle: f32,
    /// The seeded noise.
    pub random: f32,
    /// The gust's envelope.
    pub gust: f32,
    /// `(constant + sway + ripple) × strength_cycle + random + gust`.
    pub total: f32,
}

impl ProceduralWindSettings {
    /// Whether every key has its default (the table is then not written).
    pub fn is_default(&self) -> bool {
        *self == Self::default()
    }

    /// Checks the values; errors name the key (`what` names the force).
    pub fn validate(&self, what: &str) -> Result<()> {
        let bad = |msg: String| Err(Error::InvalidParameter(format!("{what}: {msg}")));
        if !self.wind_direction.is_finite() {
            return bad("procedural_wind.wind_direction is not finite".into());
        }
        if !(0.0..=180.0).contains(&self.wind_direction_noise_angle) {
            return bad(format!(
                "procedural_wind.wind_direction_noise_angle {} must be in 0..=180 degrees",
                self.wind_direction_noise_angle
            ));
        }
        if !(self.time_scale.is_finite() && (0.0..=1.0e3).contains(&self.time_scale)) {
            return bad(format!(
                "procedural_wind.time_scale {} must be in 0..=1000",
                self.time_scale
            ));
        }
        for (key, v) in [
            (
                "wind_direction_noise_period",
                self.wind_direction_noise_period,
            ),
            ("sway_period", self.sway_period),
            ("ripple_period", self.ripple_period),
            ("strength_cycle_period", self.strength_cycle_period),
            ("random_force_period", self.random_force_period),
        ] {
            if !(v.is_finite() && (MIN_PERIOD..=1.0e6).contains(&v)) {
                return bad(format!(
                    "procedural_wind.{key} {v} must be a period in {MIN_PERIOD}..=1e6 seconds"
                ));
            }
        }
        let [lo, hi] = self.strength_cycle_range;
        for (key, v) in [
            ("constant_force", self.constant_force),
            ("sway_force", self.sway_force),
            ("ripple_force", self.ripple_force),
            ("random_force", self.random_force),
            ("strength_cycle_range", lo),
            ("strength_cycle_range", hi),
        ] {
            if !(v.is_finite() && v.abs() <= MAX_STRENGTH) {
                return bad(format!(
                    "procedural_wind.{key} {v} must be finite, within ±{MAX_STRENGTH:e}"
                ));
            }
        }
        if lo > hi {
            return bad(format!(
                "procedural_wind.strength_cycle_range [{lo}, {hi}] has min > max"
            ));
        }
        for (key, v) in [
            ("sway_phase_offset", self.sway_phase_offset),
            ("ripple_phase_offset", self.ripple_phase_offset),
            ("ripple_tip_phase_delay", self.ripple_tip_phase_delay),
            (
                "strength_cycle_phase_offset",
                self.strength_cycle_phase_offset,
            ),
        ] {
            if !(v.is_finite() && v.abs() <= 1.0e6) {
                return bad(format!(
                    "procedural_wind.{key} {v} must be an angle within ±1e6 degrees"
                ));
            }
        }
        Ok(())
    }

    /// The travelling sine at `time` and length rate `x`.
    pub fn ripple(&self, time: f32, x: f32) -> f32 {
        let two_pi = std::f32::consts::PI * 2.0;
        self.ripple_force
            * (two_pi * time / self.ripple_period.max(MIN_PERIOD)
                - (x * self.ripple_tip_phase_delay).to_radians()
                + self.ripple_phase_offset.to_radians())
            .sin()
    }

    /// Every part at the wind's own `time`, length rate `x`, with a gust of `gust`
    /// (KawaiiPhysics' `ComputeWindSample`); `seed` drives the noise.
    pub fn sample(&self, time: f32, x: f32, gust: f32, seed: u64) -> WindSample {
        let two_pi = std::f32::consts::PI * 2.0;
        let sway = self.sway_force
            * (two_pi * time / self.sway_period.max(MIN_PERIOD)
                + self.sway_phase_offset.to_radians())
            .sin();
        let [lo, hi] = self.strength_cycle_range;
        let cycle = 0.5
            * (1.0
                + (two_pi * time / self.strength_cycle_period.max(MIN_PERIOD)
                    + self.strength_cycle_phase_offset.to_radians())
                .sin());
        let strength_cycle = lo + cycle * (hi - lo);
        let random = self.random_force
            * smooth_noise(
                time / self.random_force_period.max(MIN_PERIOD),
                ue_seed(seed),
                0,
            );
        let ripple = self.ripple(time, x);
        WindSample {
            constant: self.constant_force,
            sway,
            ripple,
            strength_cycle,
            random,
            gust,
            total: (self.constant_force + sway + ripple) * strength_cycle + random + gust,
        }
    }

    /// The wind's direction at `time` (unit): `wind_direction`, wandering inside the cone
    /// of `wind_direction_noise_angle` by two channels of the seeded noise.
    pub fn direction(&self, time: f32, seed: u64) -> Vec3 {
        let base = safe_direction(self.wind_direction);
        if self.wind_direction_noise_angle <= 0.0 {
            return base;
        }
        let u = time / self.wind_direction_noise_period.max(MIN_PERIOD);
        let s = ue_seed(seed);
        cone_noise(
            base,
            smooth_noise(u, s, 1),
            smooth_noise(u, s, 2),
            self.wind_direction_noise_angle,
        )
    }
}

/// The seed as KawaiiPhysics' `int32 Seed` (its low 32 bits).
fn ue_seed(seed: u64) -> i32 {
    seed as u32 as i32
}

/// A unit direction, +X when `v` has none (KawaiiPhysics' `SafeDirectionOrForward`).
fn safe_direction(v: Vec3) -> Vec3 {
    let n = ue_safe_normal(v);
    if n.abs().max_element() <= SMALL {
        Vec3::X
    } else {
        n
    }
}

/// Unreal's `GetSafeNormal`: zero for a vector whose squared length is under 1e-8.
fn ue_safe_normal(v: Vec3) -> Vec3 {
    let sq = v.length_squared();
    if sq == 1.0 {
        v
    } else if sq < 1e-8 {
        Vec3::ZERO
    } else {
        v * (1.0 / sq.sqrt())
    }
}

/// `base` tilted toward the disk offset `(nx, ny)` by up to `half_angle` degrees
/// (KawaiiPhysics' `ApplyConeNoiseToDirection`; the disk's axes are Unreal's
/// `FindBestAxisVectors` of `base`).
fn cone_noise(base: Vec3, nx: f32, ny: f32, half_angle: f32) -> Vec3 {
    let half = half_angle.max(0.0).to_radians();
    if half <= SMALL {
        return base;
    }
    let mut disk = glam::Vec2::new(nx, ny);
    let len = disk.length();
    if len <= SMALL {
        return base;
    }
    if len > 1.0 {
        disk /= len;
    }
    let (ax, ay) = best_axes(base);
    let offset = ue_safe_normal(ax * disk.x + ay * disk.y);
    let angle = half * len.min(1.0);
    ue_safe_normal(base * angle.cos() + offset * angle.sin())
}

/// Unreal's `FVector::FindBestAxisVectors`: two axes across `v`.
fn best_axes(v: Vec3) -> (Vec3, Vec3) {
    let n = v.abs();
    let a = if n.z > n.x && n.z > n.y {
        Vec3::X
    } else {
        Vec3::Z
    };
    let a = ue_safe_normal(a - v * a.dot(v));
    (a, a.cross(v))
}

/// A hash of the seed, a grid cell and a channel (KawaiiPhysics' `StableHash`: FNV-1a,
/// then a 32-bit finaliser).
pub fn stable_hash(seed: i32, cell: i32, channel: i32) -> u32 {
    let mut h: u32 = 0x811C_9DC5;
    for v in [seed as u32, cell as u32, channel as u32] {
        h ^= v;
        h = h.wrapping_mul(0x0100_0193);
    }
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846C_A68B);
    h ^= h >> 16;
    h
}

/// The value of grid cell `cell` in [-1, 1): the first draw of Unreal's `FRandomStream`
/// seeded with the cell's hash (KawaiiPhysics' `NoiseValueAt`).
fn noise_at(cell: i32, seed: i32, channel: i32) -> f32 {
    let s = stable_hash(seed, cell, channel)
        .wrapping_mul(196_314_165)
        .wrapping_add(907_633_515);
    let fraction = f32::from_bits(0x3F80_0000 | (s >> 9)) - 1.0;
    -1.0 + 2.0 * fraction
}

/// Smooth value noise at `u`: the two neighbouring cells' values blended by smoothstep
/// (KawaiiPhysics' `SampleSmoothNoise`).
pub fn smooth_noise(u: f32, seed: i32, channel: i32) -> f32 {
    let floor = u.floor();
    let cell = floor as i32;
    let a = u - floor;
    let s = a * a * (3.0 - 2.0 * a);
    let (v0, v1) = (
        noise_at(cell, seed, channel),
        noise_at(cell.wrapping_add(1), seed, channel),
    );
    v0 + s * (v1 - v0)
}

/// A gust: a strength that rises, holds and decays on the wind's clock (gone once it
/// has decayed or is stopped at once).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct Gust {
    pub start: f32,
    pub strength: f32,
    pub rise: f32,
    pub hold: f32,
    pub decay: f32,
}

impl Gust {
    /// Its strength at wind time `t` (KawaiiPhysics' `EvaluateActiveGust`).
    pub(crate) fn at(&self, t: f32) -> f32 {
        self.strength
            * super::overrides::envelope_alpha(self.rise, self.hold, self.decay, t - self.start)
    }
}

/// A gust of a procedural wind (KawaiiPhysics' `TriggerProceduralWindGust`): its strength
/// rises from 0 over `rise` seconds of the wind's clock, holds for `hold`, and decays to 0
/// over `decay`; it adds to the wind's total (not scaled by the strength cycle).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GustRequest {
    /// The peak strength (the push units of the wind's other parts).
    pub strength: f32,
    /// Seconds from 0 to the peak.
    pub rise: f32,
    /// Seconds at the peak.
    pub hold: f32,
    /// Seconds from the peak to 0.
    pub decay: f32,
}

impl GustRequest {
    /// An error naming a strength that is not finite (or beyond ±1e6) or a time that is
    /// negative or not finite.
    pub fn check(&self) -> Result<()> {
        if !(self.strength.is_finite() && self.strength.abs() <= MAX_STRENGTH) {
            return Err(Error::InvalidParameter(format!(
                "gust: the strength {} must be finite, within ±{MAX_STRENGTH:e}",
                self.strength
            )));
        }
        for (k, v) in [
            ("rise", self.rise),
            ("hold", self.hold),
            ("decay", self.decay),
        ] {
            if !(v.is_finite() && (0.0..=1.0e6).contains(&v)) {
                return Err(Error::InvalidParameter(format!(
                    "gust: {k} {v} s must be a time in 0..=1e6"
                )));
            }
        }
        Ok(())
    }
}

/// The most gusts one wind carries at once (a newer one drops the oldest, as
/// KawaiiPhysics caps its transient forces).
pub const MAX_GUSTS: usize = 8;

/// One chain's wind clock: its time, its gusts, and the requests not yet taken in.
#[derive(Debug, Clone, Default)]
pub(crate) struct WindClock {
    pub time: f32,
    pub gusts: Vec<Gust>,
    pub starts: Vec<GustRequest>,
    pub stop: Option<f32>,
}

impl WindClock {
    /// Takes in the requests (the starts, then a stop: a stop in the same frame wins, as
    /// KawaiiPhysics' `ConsumePendingRequests`), then advances the clock by `dt` ×
    /// `time_scale`. Returns the gusts' strength now.
    pub(crate) fn step(&mut self, dt: f32, time_scale: f32) -> f32 {
        for r in self.starts.drain(..) {
            if self.gusts.len() >= MAX_GUSTS {
                self.gusts.remove(0);
            }
            self.gusts.push(Gust {
                start: self.time,
                strength: r.strength,
                rise: r.rise,
                hold: r.hold,
                decay: r.decay,
            });
        }
        if let Some(blend_out) = self.stop.take() {
            let now = self.time;
            if blend_out <= SMALL {
                self.gusts.clear();
            }
            for g in &mut self.gusts {
                *g = Gust {
                    start: now,
                    strength: g.at(now),
                    rise: 0.0,
                    hold: 0.0,
                    decay: blend_out,
                };
            }
        }
        self.time += dt * time_scale;
        let t = self.time;
        self.gusts
            .retain(|g| t - g.start < g.rise + g.hold + g.decay);
        self.gusts.iter().map(|g| g.at(t)).sum()
    }
}
