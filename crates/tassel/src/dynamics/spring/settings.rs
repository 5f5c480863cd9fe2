//! Spring settings: plain data.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// One spring bone (a `[[spring]]` table of the rig file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SpringSettings {
    /// A name for messages.
    pub name: String,
    /// The bone on the spring.
    pub bone: String,
    /// Spring stiffness k, 1/s² (acceleration per metre of error; ω₀ = √k). ≥ 0.
    pub stiffness: f32,
    /// Damping b, 1/s (acceleration per m/s of velocity; ζ = b / 2√k). ≥ 0.
    pub damping: f32,
    /// Fixed step, seconds (0 < step ≤ 0.1).
    pub fixed_time_step: f32,
    /// Above this many metres of error the bone snaps back to its target (0 = off).
    pub error_reset_threshold: f32,
    /// Damping above this is scaled down (b·step ≥ 1 would overshoot); 1/s, > 0.
    pub cutoff_damping: f32,
    /// How much of the owner's (character's) velocity carries the bone along each step,
    /// 0..=1. 1 (Unreal's behaviour): steady locomotion causes no lag, only the animation's
    /// own motion swings the bone. 0: the bone keeps its world velocity, so starts, stops
    /// and turns swing it too.
    pub owner_velocity_scale: f32,
    /// Largest displacement from the target, metres (0 = no limit).
    pub limit_displacement: f32,
    /// Translation channels (character space axes) the displacement may use.
    pub translate: [bool; 3],
    /// Turn the bone by the swing from its parent's animated direction to the displaced one.
    pub use_rotation: bool,
    /// Rotation channels (about the character's X, Y, Z) the swing may use.
    pub rotate: [bool; 3],
    /// `fixed` mode: at most this many steps per frame; longer hitches drop time.
    pub max_steps_per_frame: u32,
}

impl Default for SpringSettings {
    fn default() -> Self {
        Self {
            name: String::new(),
            bone: String::new(),
            stiffness: 50.0,
            damping: 4.0,
            fixed_time_step: 1.0 / 120.0,
            error_reset_threshold: 0.5,
            cutoff_damping: 84.0,
            owner_velocity_scale: 1.0,
            limit_displacement: 0.0,
            translate: [true; 3],
            use_rotation: true,
            rotate: [true; 3],
            max_steps_per_frame: 24,
        }
    }
}

impl SpringSettings {
    /// Checks every parameter; errors name the spring and the parameter.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| {
            Err(Error::InvalidParameter(format!(
                "spring '{}': {m}",
                self.name
            )))
        };
        for (p, v) in [
            ("stiffness", self.stiffness),
            ("damping", self.damping),
            ("error_reset_threshold", self.error_reset_threshold),
            ("limit_displacement", self.limit_displacement),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{p} is {v}; it must be finite and ≥ 0"));
            }
        }
        if !(0.0..=1.0).contains(&self.owner_velocity_scale) {
            return bad(format!(
                "owner_velocity_scale is {}; it must be between 0 and 1",
                self.owner_velocity_scale
            ));
        }
        let min_step = crate::limits::MIN_TIME_STEP;
        if !(self.fixed_time_step.is_finite()
            && self.fixed_time_step >= min_step
            && self.fixed_time_step <= 0.1)
        {
            return bad(format!(
                "fixed_time_step is {}; it must be in [{min_step}, 0.1] s",
                self.fixed_time_step
            ));
        }
        if !(self.cutoff_damping.is_finite() && self.cutoff_damping > 0.0) {
            return bad(format!(
                "cutoff_damping is {}; it must be > 0",
                self.cutoff_damping
            ));
        }
        let max_steps = crate::limits::MAX_STEPS_PER_FRAME;
        if !(1..=max_steps).contains(&self.max_steps_per_frame) {
            return bad(format!(
                "max_steps_per_frame is {}; it must be 1..={max_steps}",
                self.max_steps_per_frame
            ));
        }
        for (p, v) in [
            ("error_reset_threshold", self.error_reset_threshold),
            ("limit_displacement", self.limit_displacement),
        ] {
            if v > 1000.0 {
                return bad(format!("{p} is {v}; it must be at most 1000"));
            }
        }
        if self.error_reset_threshold == 0.0 && self.limit_displacement == 0.0 {
            return bad(
                "error_reset_threshold and limit_displacement are both 0 (off): nothing \
                 would bound the bone after a teleport; set one of them"
                    .into(),
            );
        }
        let growth = self.step_growth();
        if growth > 1.0 + 1e-9 {
            return bad(format!(
                "stiffness {} and damping {} are unstable with fixed_time_step {} s: each \
                 step would multiply the motion by {growth:.3}; lower them or the step",
                self.stiffness, self.damping, self.fixed_time_step
            ));
        }
        Ok(())
    }

    /// The spectral radius of one integration step (kick-drift-kick with Unreal's forces,
    /// the damping cut-off applied): above 1 the spring gains energy every step and runs
    /// away to infinity whatever the motion (found by the simulation fuzzer). Real rigs are
    /// far below the edge (the default: k·h² = 0.0035, where instability needs ≈ 4).
    pub fn step_growth(&self) -> f64 {
        let h = self.fixed_time_step as f64;
        let safety = if self.damping > self.cutoff_damping {
            self.cutoff_damping as f64 / self.damping as f64
        } else {
            1.0
        };
        let (k, b) = (self.stiffness as f64 * safety, self.damping as f64 * safety);
        // (x, v) → (x', v'): v½ = c·v − a·x, x' = x + h·v½, v' = c·v½ − a·x' with
        // a = h·k/2, c = 1 − h·b/2.
        let (a, c) = (0.5 * h * k, 1.0 - 0.5 * h * b);
        let m = [
            [1.0 - h * a, h * c],
            [-a * c - a * (1.0 - h * a), c * c - a * h * c],
        ];
        let tr = m[0][0] + m[1][1];
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        let disc = tr * tr - 4.0 * det;
        if disc >= 0.0 {
            let r = disc.sqrt();
            ((tr + r) / 2.0).abs().max(((tr - r) / 2.0).abs())
        } else {
            det.abs().sqrt()
        }
    }
}
