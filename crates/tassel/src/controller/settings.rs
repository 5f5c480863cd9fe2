//! The controller's configuration and the character's capsule: plain data.

use crate::error::{Error, Result};
use glam::Vec3;

/// The character's collision shape: a capsule along the controller's up axis (the local Y
/// of the pose's rotation), centred on the pose's translation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharacterCapsule {
    /// Radius, metres (> 0).
    pub radius: f32,
    /// Half the length of the axis segment between the two sphere centres, metres (≥ 0).
    /// The capsule is `2 · (half_height + radius)` tall.
    pub half_height: f32,
}

impl CharacterCapsule {
    /// A capsule of total `height` (metres) and `radius`.
    pub fn with_height(height: f32, radius: f32) -> Self {
        Self {
            radius,
            half_height: (0.5 * height - radius).max(0.0),
        }
    }

    /// Distance from the centre to the bottom, metres.
    pub fn half_total_height(&self) -> f32 {
        self.half_height + self.radius
    }

    pub(crate) fn validate(&self) -> Result<()> {
        if !(self.radius.is_finite() && self.radius > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "capsule radius {} must be finite and > 0",
                self.radius
            )));
        }
        if !(self.half_height.is_finite() && self.half_height >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "capsule half height {} must be finite and ≥ 0",
                self.half_height
            )));
        }
        Ok(())
    }
}

/// How a kinematic character moves: plain data with game-typical defaults (after rapier's
/// `KinematicCharacterController`). Call [`ControllerSettings::move_shape`] every frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerSettings {
    /// World up (unit length after normalisation; default +Y). Slopes, steps, snapping and
    /// "grounded" are measured against it.
    pub up: Vec3,
    /// Gap kept between the capsule and the level, metres (default 0.01, ≥ 0). Sweeps stop
    /// this far from surfaces so that the next frame starts free.
    pub skin: f32,
    /// Highest step climbed automatically, metres (default 0.3, ≥ 0; 0 turns stepping off).
    pub max_step_height: f32,
    /// Free room needed on top of a step, measured beyond the point where the capsule lands
    /// on it, metres (default 0.1, ≥ 0). Narrower ledges are not climbed.
    pub min_step_width: f32,
    /// Steepest slope walked up, degrees from horizontal (default 45, in `[0, 90]`).
    /// Steeper slopes block horizontal motion like walls.
    pub max_climb_angle: f32,
    /// Slopes at least this steep, degrees, make the character slide down under the
    /// caller's downward motion (default 45, in `[0, 90]`). Gentler slopes hold it.
    pub min_slide_angle: f32,
    /// Largest drop the character is pulled down onto the ground by when it was grounded
    /// and is not moving up, metres (default 0.3, ≥ 0): walking down stairs and slopes
    /// stays on the ground instead of flying off.
    pub snap_to_ground: f32,
    /// Most sweeps per call for collide-and-slide (default 6, 1..=64). Each contact
    /// plane met (a wall, a corner's second wall, the floor) takes one.
    pub iterations: u32,
    /// The collision groups the character collides with, one bit each (default all): a
    /// level collider is solid for it when `collider.groups & collide_with != 0`.
    pub collide_with: u32,
}

impl Default for ControllerSettings {
    fn default() -> Self {
        Self {
            up: Vec3::Y,
            skin: 0.01,
            max_step_height: 0.3,
            min_step_width: 0.1,
            max_climb_angle: 45.0,
            min_slide_angle: 45.0,
            snap_to_ground: 0.3,
            iterations: 6,
            collide_with: u32::MAX,
        }
    }
}

impl ControllerSettings {
    /// Checks every field; the error names the field and its range.
    pub fn validate(&self) -> Result<()> {
        let bad = |s: String| Err(Error::InvalidParameter(format!("controller: {s}")));
        if !self.up.is_finite() || self.up.length() < 1e-6 {
            return bad(format!("up {} must be finite and non-zero", self.up));
        }
        for (name, v) in [
            ("skin", self.skin),
            ("max_step_height", self.max_step_height),
            ("min_step_width", self.min_step_width),
            ("snap_to_ground", self.snap_to_ground),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(format!("{name} {v} must be finite and ≥ 0"));
            }
        }
        for (name, v) in [
            ("max_climb_angle", self.max_climb_angle),
            ("min_slide_angle", self.min_slide_angle),
        ] {
            if !(v.is_finite() && (0.0..=90.0).contains(&v)) {
                return bad(format!("{name} {v}° must be within 0..=90 degrees"));
            }
        }
        if !(1..=64).contains(&self.iterations) {
            return bad(format!("iterations {} must be 1..=64", self.iterations));
        }
        Ok(())
    }
}
