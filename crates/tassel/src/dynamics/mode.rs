//! One switch for how a whole character steps: the `--mode` of `tassel simulate`,
//! `bake`, `render` and `plot`.

use super::chain::TimeMode;
use super::vrm::{VrmMode, VrmOptions};
use super::RigSettings;
use crate::error::{Error, Result};

/// How a character's secondary motion is stepped. The default is [`SimMode::Fixed`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SimMode {
    /// VRM springs exactly as the VRM specification steps them (once per frame, the look
    /// depends on the frame rate); rig chains keep the mode the rig file gives them.
    Spec,
    /// VRM springs and chains at a fixed internal rate: the look does not depend on the
    /// frame rate. The default.
    #[default]
    Fixed,
    /// Chains frame by frame as KawaiiPhysics does (VRM springs by the specification): the
    /// frame-rate-dependent pair, for comparison.
    Classic,
    /// VRM springs as three-vrm 3.5.5 runs them in a web app ([`VrmMode::ThreeVrm`]): what
    /// web viewers show; rig chains keep the mode the rig file gives them.
    ThreeVrm,
}

impl SimMode {
    /// `spec`, `fixed`, `classic` or `three-vrm`.
    pub fn name(self) -> &'static str {
        match self {
            SimMode::Spec => "spec",
            SimMode::Fixed => "fixed",
            SimMode::Classic => "classic",
            SimMode::ThreeVrm => "three-vrm",
        }
    }

    /// Settles the mode for a rig (and a model with or without VRM springs) and sets the
    /// rig's chains to it. Without a requested mode: `fixed` for a model with VRM springs,
    /// else the first chain's own mode (the rig file's choice; `fixed` unless it says
    /// `classic`). `spec` without VRM springs is an error; `fixed` or
    /// `classic` asked for explicitly set every chain's mode.
    pub fn apply(
        requested: Option<SimMode>,
        rig: &mut RigSettings,
        has_vrm: bool,
    ) -> Result<(SimMode, VrmOptions)> {
        let mode = match requested {
            Some(m) => m,
            None if has_vrm => SimMode::Fixed,
            None => match rig.chains.first().map(|c| c.mode) {
                Some(TimeMode::Classic) => SimMode::Classic,
                _ => SimMode::Fixed,
            },
        };
        if matches!(mode, SimMode::Spec | SimMode::ThreeVrm) && !has_vrm {
            return Err(Error::InvalidParameter(format!(
                "mode {} is a VRM spring-bone mode and this model has no VRM springs; use fixed or classic",
                mode.name()
            )));
        }
        if requested.is_some() && matches!(mode, SimMode::Fixed | SimMode::Classic) {
            for c in &mut rig.chains {
                c.mode = if mode == SimMode::Classic {
                    TimeMode::Classic
                } else {
                    TimeMode::Fixed
                };
            }
        }
        let options = VrmOptions {
            mode: match mode {
                SimMode::Fixed => VrmMode::Fixed,
                SimMode::ThreeVrm => VrmMode::ThreeVrm,
                SimMode::Spec | SimMode::Classic => VrmMode::Spec,
            },
            ..VrmOptions::default()
        };
        Ok((mode, options))
    }
}
