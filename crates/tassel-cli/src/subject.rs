//! The character a command works on: a file (its skeleton, clips and VRM springs) or the
//! embedded one, with the rig that drives its secondary motion.

use std::path::{Path, PathBuf};
use tassel::anim::Clip;
use tassel::dynamics::vrm::VrmSpringBones;
use tassel::dynamics::{RigSettings, SimMode};
use tassel::{builtin, CharacterSim, Skeleton};
use tassel_gltf::Sway;

/// `--mode` on the command line.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Mode {
    Spec,
    Fixed,
    Classic,
    /// VRM springs as three-vrm 3.5.5 runs them in a web app.
    ThreeVrm,
    /// Chains as KawaiiPhysics 1.21 steps them by default (fixed substepping).
    Kawaii,
    /// Bone cloths as SPCRJointDynamicsUE4 runs them.
    Spcr,
}

impl From<Mode> for SimMode {
    fn from(m: Mode) -> SimMode {
        match m {
            Mode::Spec => SimMode::Spec,
            Mode::Fixed => SimMode::Fixed,
            Mode::Classic => SimMode::Classic,
            Mode::ThreeVrm => SimMode::ThreeVrm,
            Mode::Kawaii => SimMode::Kawaii,
            Mode::Spcr => SimMode::Spcr,
        }
    }
}

/// The largest rig file read (16 MiB: far beyond any real rig, far below any memory
/// trouble).
pub const MAX_RIG_BYTES: u64 = 16 << 20;

pub fn read_rig(path: &PathBuf) -> Result<RigSettings, String> {
    use std::io::Read;
    let fail = |e: std::io::Error| format!("{}: {e}", path.display());
    let file = std::fs::File::open(path).map_err(fail)?;
    if !file.metadata().map_err(fail)?.is_file() {
        return Err(format!("{}: not a regular file", path.display()));
    }
    let mut text = String::new();
    file.take(MAX_RIG_BYTES + 1)
        .read_to_string(&mut text)
        .map_err(fail)?;
    if text.len() as u64 > MAX_RIG_BYTES {
        return Err(format!(
            "{}: the rig file is larger than the limit of {MAX_RIG_BYTES} bytes",
            path.display()
        ));
    }
    RigSettings::from_toml_str(&text).map_err(|e| format!("{}: {e}", path.display()))
}

pub struct Subject {
    /// For titles and messages.
    pub name: String,
    pub skeleton: Skeleton,
    pub clips: Vec<Clip>,
    pub vrm: VrmSpringBones,
    pub rig: RigSettings,
}

/// `FILE` or `--builtin`, with `--rig` (required for a file without VRM springs; replaces
/// the embedded character's own rig).
pub fn load(
    file: Option<&PathBuf>,
    builtin: bool,
    rig: Option<&PathBuf>,
) -> Result<Subject, String> {
    match (file, builtin) {
        (Some(_), true) => Err("give either FILE or --builtin, not both".into()),
        (None, false) => Err("give a FILE or --builtin".into()),
        (None, true) => {
            let c = builtin::character();
            Ok(Subject {
                name: "BUILTIN".into(),
                skeleton: c.skeleton,
                clips: c.clips,
                vrm: VrmSpringBones::default(),
                rig: match rig {
                    Some(p) => read_rig(p)?,
                    None => c.rig,
                },
            })
        }
        (Some(path), false) => {
            let model = tassel_gltf::load(path).map_err(|e| e.to_string())?;
            let vrm = model.vrm.map(|v| v.springs).unwrap_or_default();
            let rig = rig_or_vrm(rig, !vrm.is_empty(), path)?;
            Ok(Subject {
                name: path
                    .file_name()
                    .map(|n| n.to_string_lossy().to_string())
                    .unwrap_or_default(),
                skeleton: model.skeleton,
                clips: model.clips,
                vrm,
                rig,
            })
        }
    }
}

/// The rig file, or an empty rig for a model whose VRM springs are enough.
pub fn rig_or_vrm(
    rig: Option<&PathBuf>,
    has_vrm: bool,
    input: &Path,
) -> Result<RigSettings, String> {
    match rig {
        Some(p) => read_rig(p),
        None if has_vrm => Ok(RigSettings::default()),
        None => Err(format!(
            "{}: the file has no VRM spring bones; give --rig RIG.toml",
            input.display()
        )),
    }
}

/// The solvers for `skeleton`: the VRM springs and the rig, stepped in `mode`.
pub fn make_sim(
    skeleton: &Skeleton,
    vrm: &VrmSpringBones,
    rig: &RigSettings,
    mode: Option<Mode>,
) -> Result<(CharacterSim, SimMode), String> {
    let mut rig = rig.clone();
    let (mode, options) = SimMode::apply(mode.map(Mode::into), &mut rig, !vrm.is_empty())
        .map_err(|e| format!("--mode: {e}"))?;
    let sim = CharacterSim::with_vrm(skeleton.clone(), &rig, vrm, options)
        .map_err(|e| format!("rig: {e}"))?;
    Ok((sim, mode))
}

impl Subject {
    pub fn sim(&self, mode: Option<Mode>) -> Result<(CharacterSim, SimMode), String> {
        make_sim(&self.skeleton, &self.vrm, &self.rig, mode)
    }

    /// The index of the named clip, or of the first clip without a name; `None` (the rest
    /// pose) for a file without clips.
    pub fn clip(&self, name: Option<&str>) -> Result<Option<usize>, String> {
        match name {
            Some(n) => self
                .clips
                .iter()
                .position(|c| c.name == n)
                .map(Some)
                .ok_or_else(|| {
                    let names: Vec<String> =
                        self.clips.iter().map(|c| format!("'{}'", c.name)).collect();
                    format!(
                        "{}: no clip named '{n}'; the file has {}",
                        self.name,
                        if names.is_empty() {
                            "no clips".to_string()
                        } else {
                            names.join(", ")
                        }
                    )
                }),
            None => Ok((!self.clips.is_empty()).then_some(0)),
        }
    }
}

/// `FILE | --builtin`, `--clip`, `--rig`: what `render` and `plot` play.
#[derive(clap::Args)]
pub struct SubjectArgs {
    /// The model (.glb, .gltf, .vrm); omit with --builtin.
    file: Option<PathBuf>,
    /// Use the embedded character (its own rig unless --rig is given).
    #[arg(long)]
    pub builtin: bool,
    /// The clip to play. Default: the first; a file without clips holds its rest pose.
    #[arg(long)]
    clip: Option<String>,
    /// Rig file (TOML); optional for a VRM.
    #[arg(long)]
    rig: Option<PathBuf>,
}

impl SubjectArgs {
    /// The character and the chosen clip (`None`: the rest pose).
    pub fn load(&self) -> Result<(Subject, Option<usize>), String> {
        let subject = load(self.file.as_ref(), self.builtin, self.rig.as_ref())?;
        let clip = subject.clip(self.clip.as_deref())?;
        Ok((subject, clip))
    }
}

/// `--sway X,Y,Z --sway-hz F`: the whole character moved back and forth.
#[derive(clap::Args)]
pub struct SwayArgs {
    /// Move the whole character back and forth: the largest offset as X,Y,Z in the file's
    /// units (e.g. 0.1,0,0). `bake` keys the root nodes with the motion. Gives the springs
    /// of a file without clips something to swing from.
    #[arg(long, value_parser = parse_vec3, allow_hyphen_values = true)]
    sway: Option<glam::Vec3>,
    /// Cycles per second of --sway.
    #[arg(long, default_value_t = 1.0)]
    sway_hz: f32,
}

impl SwayArgs {
    pub fn sway(&self) -> Option<Sway> {
        self.sway.map(|amplitude| Sway {
            amplitude,
            frequency: self.sway_hz,
        })
    }
}

/// `X,Y,Z` as a vector.
pub fn parse_vec3(text: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let bad = || format!("'{text}' is not X,Y,Z (three numbers separated by commas)");
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0f32; 3];
    for (i, p) in parts.iter().enumerate() {
        v[i] = p.parse().map_err(|_| bad())?;
        if !v[i].is_finite() {
            return Err(bad());
        }
    }
    Ok(glam::Vec3::from_array(v))
}
