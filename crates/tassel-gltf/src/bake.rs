//! Baking secondary motion into a model's clips: play a clip (looped through a warm-up),
//! run the character's solvers frame by frame, and key the bones they move.

use crate::error::{GltfError, PlayError};
use crate::export::{BakedClip, BakedTrack};
use crate::import::Model;
use glam::{Quat, Vec3};
use tassel::anim::Clip;
use tassel::{CharacterSim, Transform};

/// How a clip is baked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BakeOptions {
    /// Key rate, frames per second (1..=1000).
    pub fps: f32,
    /// Seconds the clip plays, looped, before its first key, so the solvers start the clip
    /// settled instead of from the rest pose (0..=600).
    pub warmup: f32,
    /// Length of the `rest` clip baked for a file without clips, seconds (0..=600].
    pub rest_duration: f32,
    /// Moves the whole character back and forth while baking (its root nodes are keyed
    /// with the motion), so that springs have something to swing from, e.g. in a file
    /// without clips.
    pub sway: Option<Sway>,
}

/// A back-and-forth motion of the whole character: `amplitude · sin(2π · frequency · t)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sway {
    /// Largest offset along each axis, in the file's units.
    pub amplitude: Vec3,
    /// Cycles per second (0 < f ≤ 100).
    pub frequency: f32,
}

impl Sway {
    /// The offset at `t` seconds.
    pub fn offset(&self, t: f32) -> Vec3 {
        self.amplitude * (std::f32::consts::TAU * self.frequency * t).sin()
    }
}

impl Default for BakeOptions {
    fn default() -> Self {
        Self {
            fps: 60.0,
            warmup: 1.0,
            rest_duration: 2.0,
            sway: None,
        }
    }
}

impl BakeOptions {
    /// Checks the ranges; the message names the option.
    pub fn validate(&self) -> Result<(), GltfError> {
        let bad = |m: String| {
            Err(GltfError::Invalid {
                path: "<bake>".into(),
                message: m,
            })
        };
        if !(self.fps.is_finite() && (1.0..=1000.0).contains(&self.fps)) {
            return bad(format!(
                "fps {} must be a number of frames per second in 1..=1000",
                self.fps
            ));
        }
        if !(self.warmup.is_finite() && (0.0..=600.0).contains(&self.warmup)) {
            return bad(format!(
                "warmup {} must be a number of seconds in 0..=600",
                self.warmup
            ));
        }
        if !(self.rest_duration.is_finite()
            && self.rest_duration > 0.0
            && self.rest_duration <= 600.0)
        {
            return bad(format!(
                "rest duration {} must be a number of seconds in (0, 600]",
                self.rest_duration
            ));
        }
        if let Some(sw) = self.sway {
            if !(sw.amplitude.is_finite()
                && sw.frequency.is_finite()
                && sw.frequency > 0.0
                && sw.frequency <= 100.0)
            {
                return bad(format!(
                    "sway {} at {} Hz: the amplitude must be finite and the frequency in (0, 100]",
                    sw.amplitude, sw.frequency
                ));
            }
        }
        Ok(())
    }

    /// The character's transform at `t` seconds (the sway, or none).
    pub fn component(&self, t: f32) -> Transform {
        match self.sway {
            Some(sw) => Transform::from_translation(sw.offset(t)),
            None => Transform::IDENTITY,
        }
    }
}

/// What to bake: one of the model's clips, or the rest pose held (for a file without
/// clips, e.g. a VRM: the springs settle under gravity).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BakeSource {
    /// The model's clip (= glTF animation) of this index.
    Clip(usize),
    /// The rest pose for [`BakeOptions::rest_duration`] seconds, as a new clip `rest`
    /// (`sway` with [`BakeOptions::sway`]).
    Rest,
}

impl BakeSource {
    /// The baked clip's name: the clip's own, or `rest` (`sway` with a sway).
    pub fn name(&self, model: &Model, options: &BakeOptions) -> String {
        match *self {
            BakeSource::Clip(i) => model
                .clips
                .get(i)
                .map(|c| c.name.clone())
                .unwrap_or_default(),
            BakeSource::Rest if options.sway.is_some() => "sway".to_string(),
            BakeSource::Rest => "rest".to_string(),
        }
    }
}

/// The most keys (frames × simulated bones) one baked clip may hold (8 M: with the
/// translations, about 240 MB before export).
pub const MAX_BAKE_KEYS: usize = 1 << 23;

/// The key times of a bake: `k / fps` up to the duration, the last key exactly at the
/// duration (a clip of length 0 gets one key).
pub fn key_times(duration: f32, fps: f32) -> Vec<f32> {
    let step = 1.0 / fps;
    let mut times = Vec::new();
    let mut k = 0u32;
    loop {
        let t = k as f32 * step;
        if t >= duration - 0.25 * step {
            break;
        }
        times.push(t);
        k += 1;
    }
    times.push(duration);
    times
}

/// One frame of [`play`], after the solvers ran.
pub struct PlayedFrame<'a> {
    /// Index into the times.
    pub index: usize,
    /// Seconds into the clip.
    pub time: f32,
    /// The animated local pose the solvers started from.
    pub animated: &'a [Transform],
    /// The character's transform.
    pub component: Transform,
    /// The simulation, its pose and states as of this frame.
    pub sim: &'a CharacterSim,
}

/// Plays `clip` (or the rest pose) through `sim`: resets it, runs the warm-up (the clip
/// looped from `-warmup` seconds; the first frame, with dt = 0, places every solver on the
/// animated pose), then one frame at each of `times` (the clip sampled exactly there, not
/// wrapped), calling `on_frame` after each. The character's transform is
/// [`BakeOptions::component`]. Errors from `sim` and from `on_frame` stop the run; an
/// `on_frame` error comes back as [`PlayError::Frame`], unchanged.
pub fn play<E>(
    sim: &mut CharacterSim,
    clip: Option<&Clip>,
    times: &[f32],
    options: &BakeOptions,
    on_frame: &mut dyn FnMut(&PlayedFrame) -> Result<(), E>,
) -> Result<(), PlayError<E>> {
    options.validate().map_err(PlayError::Options)?;
    let rest = sim.skeleton().rest().to_vec();
    let mut locals = rest.clone();
    let step = 1.0 / options.fps;
    sim.reset();
    let warm_frames = (options.warmup * options.fps).round() as u32;
    let start = -(warm_frames as f32) * step;
    let mut t_prev = start;
    for k in 0..warm_frames {
        let t = start + k as f32 * step;
        locals.copy_from_slice(&rest);
        if let Some(c) = clip {
            c.sample_looped(t, &mut locals);
        }
        let dt = if k == 0 { 0.0 } else { t - t_prev };
        sim.frame(&locals, options.component(t), dt)
            .map_err(|source| PlayError::Simulation { time: t, source })?;
        t_prev = t;
    }
    for (k, &t) in times.iter().enumerate() {
        locals.copy_from_slice(&rest);
        if let Some(c) = clip {
            c.sample(t, &mut locals);
        }
        let dt = if warm_frames == 0 && k == 0 {
            0.0
        } else {
            t - t_prev
        };
        let component = options.component(t);
        sim.frame(&locals, component, dt)
            .map_err(|source| PlayError::Simulation { time: t, source })?;
        on_frame(&PlayedFrame {
            index: k,
            time: t,
            animated: &locals,
            component,
            sim,
        })
        .map_err(PlayError::Frame)?;
        t_prev = t;
    }
    Ok(())
}

/// Bakes one clip of `model` with `sim` (built for `model.skeleton`; it is reset first).
/// The result keys every joint `sim` simulates: rotations always, translations where a
/// solver moved them; with [`BakedClip::merge_into`] set to the clip's animation, so
/// [`crate::export_glb`] keeps every other channel of that animation as it was.
/// `progress(done, total)` is called after each key.
pub fn bake_clip(
    model: &Model,
    sim: &mut CharacterSim,
    source: BakeSource,
    options: &BakeOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<BakedClip, GltfError> {
    options.validate()?;
    let invalid = |m: String| GltfError::Invalid {
        path: "<bake>".into(),
        message: m,
    };
    if sim.skeleton().len() != model.skeleton.len() {
        return Err(invalid(format!(
            "the simulation has {} joints and the model {}",
            sim.skeleton().len(),
            model.skeleton.len()
        )));
    }
    let (clip, duration, merge_into) = match source {
        BakeSource::Clip(i) => {
            let clip = model.clips.get(i).ok_or_else(|| {
                invalid(format!(
                    "clip {i} does not exist (the file has {})",
                    model.clips.len()
                ))
            })?;
            (Some(clip), clip.duration, Some(i))
        }
        BakeSource::Rest => (None, options.rest_duration, None),
    };
    let name = source.name(model, options);
    let err = |e: String| invalid(format!("clip '{name}': {e}"));
    let joints = sim.simulated_joints().to_vec();
    // Checked before anything is played or allocated: keys = frames × bones.
    let frames = (duration * options.fps).ceil() as usize + 1;
    if frames.saturating_mul(joints.len().max(1)) > MAX_BAKE_KEYS {
        return Err(err(format!(
            "{frames} frames × {} bones is more than the limit of {MAX_BAKE_KEYS} keys per clip; \
             bake at a lower --fps or a shorter clip",
            joints.len()
        )));
    }
    let times = key_times(duration, options.fps);
    // With a sway the roots carry the character's motion in the file.
    let roots: Vec<usize> = match options.sway {
        Some(_) => (0..model.skeleton.len())
            .filter(|&j| model.skeleton.parent(j).is_none())
            .collect(),
        None => Vec::new(),
    };
    let mut rotations: Vec<Vec<Quat>> = vec![Vec::with_capacity(times.len()); joints.len()];
    let mut translations: Vec<Vec<Vec3>> = vec![Vec::with_capacity(times.len()); joints.len()];
    let mut moved = vec![false; joints.len()];
    let mut root_translations: Vec<Vec<Vec3>> = vec![Vec::with_capacity(times.len()); roots.len()];
    play(sim, clip, &times, options, &mut |f| {
        let (k, t, animated, component) = (f.index, f.time, f.animated, f.component);
        let pose = f.sim.pose();
        for (i, &j) in joints.iter().enumerate() {
            let l = pose.locals[j];
            if !l.translation.is_finite() || !l.rotation.is_finite() {
                return Err(format!(
                    "joint '{}' is not finite at {t} s",
                    model.skeleton.name(j)
                ));
            }
            rotations[i].push(l.rotation);
            translations[i].push(l.translation);
            moved[i] |= l.translation != animated[j].translation;
        }
        for (i, &r) in roots.iter().enumerate() {
            root_translations[i].push(component.translation + pose.locals[r].translation);
        }
        progress(k + 1, times.len());
        Ok::<(), String>(())
    })
    .map_err(|e| err(e.to_string()))?;
    let mut tracks: Vec<BakedTrack> = joints
        .iter()
        .enumerate()
        .map(|(i, &j)| BakedTrack {
            node: model.joint_to_node[j],
            translations: moved[i].then(|| std::mem::take(&mut translations[i])),
            rotations: Some(std::mem::take(&mut rotations[i])),
            scales: None,
        })
        .collect();
    for (i, &r) in roots.iter().enumerate() {
        let node = model.joint_to_node[r];
        let keys = std::mem::take(&mut root_translations[i]);
        match tracks.iter_mut().find(|t| t.node == node) {
            Some(t) => t.translations = Some(keys),
            None => tracks.push(BakedTrack {
                node,
                translations: Some(keys),
                rotations: None,
                scales: None,
            }),
        }
    }
    Ok(BakedClip {
        name,
        times,
        tracks,
        merge_into,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn key_times_end_on_the_duration() {
        let t = key_times(1.0, 4.0);
        assert_eq!(t, vec![0.0, 0.25, 0.5, 0.75, 1.0]);
        // A duration that is not a whole number of frames: the last regular key is
        // dropped when it would land within a quarter frame of the end.
        let t = key_times(0.51, 4.0);
        assert_eq!(t, vec![0.0, 0.25, 0.51]);
        let t = key_times(0.6, 4.0);
        assert_eq!(t, vec![0.0, 0.25, 0.5, 0.6]);
        assert_eq!(key_times(0.0, 60.0), vec![0.0]);
    }
}
