//! Spring state and the frame job.

use super::settings::SpringSettings;
use crate::error::{Error, Result};
use crate::math::{normalize_or, rotation_arc, Transform};
use crate::skeleton::Skeleton;
use glam::{EulerRot, Quat, Vec3};

/// Springs compiled against a skeleton.
#[derive(Debug, Clone)]
pub struct SpringRig {
    springs: Vec<(SpringSettings, usize)>,
    joint_count: usize,
}

impl SpringRig {
    /// Resolves bone names and checks parameters.
    pub fn new(skeleton: &Skeleton, springs: &[SpringSettings]) -> Result<Self> {
        let mut out = Vec::new();
        for s in springs {
            s.validate()?;
            let j = skeleton.find(&s.bone).ok_or_else(|| Error::MissingBone {
                context: format!("spring '{}' bone", s.name),
                name: s.bone.clone(),
            })?;
            if out.iter().any(|(_, k)| *k == j) {
                return Err(Error::InvalidParameter(format!(
                    "bone '{}' is on two springs",
                    s.bone
                )));
            }
            out.push((s.clone(), j));
        }
        out.sort_by_key(|(_, j)| *j);
        Ok(Self {
            springs: out,
            joint_count: skeleton.len(),
        })
    }

    /// Number of springs.
    pub fn len(&self) -> usize {
        self.springs.len()
    }

    /// True without springs.
    pub fn is_empty(&self) -> bool {
        self.springs.is_empty()
    }

    /// The joint of spring `i`.
    pub fn joint(&self, i: usize) -> usize {
        self.springs[i].1
    }
}

#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct One {
    location: Vec3,
    velocity: Vec3,
    remaining: f32,
    prev_target: Vec3,
    /// The target of the last step (where `location` is measured from).
    step_target: Vec3,
    /// The owner's (character's) position at the last step's time: each step carries the
    /// bone by the owner's motion since then.
    step_owner: Vec3,
    /// How fast the spring's frame (the owner's velocity it is carried with) moved
    /// relative to the target over the last frame with steps: the owner velocity times its
    /// scale, less the target's velocity.
    drift: Vec3,
    initialized: bool,
}

/// Farther from the target than the spring's error reset allows (0 = no reset).
fn beyond_reset(s: &SpringSettings, d: Vec3) -> bool {
    s.error_reset_threshold > 0.0 && d.length_squared() > s.error_reset_threshold.powi(2)
}

impl One {
    /// The displacement from the target at the frame's end: the last step's deviation,
    /// moved on by the carried-over time at the velocity relative to the target. Measured
    /// from the target, never an absolute position, so the output does not lag a moving
    /// target by the carried-over time (a 1 km teleport once left a bone 485 m behind).
    fn deviation(&self) -> Vec3 {
        self.location - self.step_target + (self.velocity + self.drift) * self.remaining
    }
}

/// Per-character spring state: each bone's world location and velocity, and the time
/// carried over to the next frame.
#[derive(Debug, Clone, PartialEq)]
pub struct SpringState {
    springs: Vec<One>,
    prev_component: Option<Transform>,
    resets: u64,
}

impl SpringState {
    /// Fresh state; the first frame starts every bone at its target, at rest.
    pub fn new(rig: &SpringRig) -> Self {
        Self {
            springs: vec![One::default(); rig.len()],
            prev_component: None,
            resets: 0,
        }
    }

    /// Starts again from the targets on the next frame.
    pub fn reset(&mut self) {
        self.springs.iter_mut().for_each(|s| s.initialized = false);
        self.prev_component = None;
    }

    /// The world-space displacement of spring `i` from its target after the last frame.
    pub fn displacement(&self, i: usize) -> Vec3 {
        self.springs[i].deviation()
    }

    /// Releases spring `i` from `offset` (world space, metres) away from its last target,
    /// at rest. For tests and tools that pluck a bone.
    pub fn displace(&mut self, i: usize, offset: Vec3) {
        if let Some(s) = self.springs.get_mut(i) {
            if s.initialized && offset.is_finite() {
                s.location = s.prev_target + offset;
                s.step_target = s.prev_target;
                s.velocity = Vec3::ZERO;
                s.drift = Vec3::ZERO;
                s.remaining = 0.0;
            }
        }
    }

    /// How many error resets happened.
    pub fn reset_count(&self) -> u64 {
        self.resets
    }
}

/// One frame of every spring: reads the animated pose, writes the bones' new model
/// transforms (and locals).
#[derive(Debug)]
pub struct SpringJob<'a> {
    /// The skeleton.
    pub skeleton: &'a Skeleton,
    /// The compiled springs.
    pub rig: &'a SpringRig,
    /// Their state.
    pub state: &'a mut SpringState,
    /// The character's world transform.
    pub component: Transform,
    /// Frame time, seconds.
    pub dt: f32,
    /// In: the pose so far. Out: spring bones moved and turned.
    pub locals: &'a mut [Transform],
    /// In: model transforms of `locals`. Out: recomputed.
    pub models: &'a mut [Transform],
}

impl SpringJob<'_> {
    /// Checks sizes and inputs.
    pub fn validate(&self) -> Result<()> {
        let n = self.skeleton.len();
        if self.rig.joint_count != n || self.locals.len() != n || self.models.len() != n {
            return Err(Error::LengthMismatch {
                what: "spring pose",
                expected: n,
                got: self.locals.len(),
            });
        }
        if !(self.dt.is_finite() && self.dt >= 0.0) {
            return Err(Error::InvalidTimeStep(self.dt));
        }
        if !self.component.is_finite() {
            return Err(Error::NonFinite("character transform".into()));
        }
        Ok(())
    }

    /// Validates, then steps every spring and writes the bones. Never allocates.
    pub fn run(self) -> Result<()> {
        self.validate()?;
        let comp = self.component;
        // A velocity is only measured over a real step of time: a frame shorter than the
        // shortest time step (say 1e-30 s) would turn any motion into an infinite speed.
        let measurable = self.dt >= crate::limits::MIN_TIME_STEP;
        let prev_owner = self
            .state
            .prev_component
            .map_or(comp.translation, |p| p.translation);
        self.state.prev_component = Some(comp);
        let inv_rot = comp.rotation.inverse();
        for (i, (s, j)) in self.rig.springs.iter().enumerate() {
            let j = *j;
            let st = &mut self.state.springs[i];
            let target = comp.transform_point(self.models[j].translation);
            if !st.initialized || !st.location.is_finite() || !st.velocity.is_finite() {
                *st = One {
                    location: target,
                    velocity: Vec3::ZERO,
                    remaining: 0.0,
                    prev_target: target,
                    step_target: target,
                    step_owner: comp.translation,
                    drift: Vec3::ZERO,
                    initialized: true,
                };
            }
            let h = s.fixed_time_step;
            let carried = st.remaining;
            st.remaining += self.dt;
            let mut steps = (st.remaining / h).floor() as u32;
            if steps > s.max_steps_per_frame {
                st.remaining -= (steps - s.max_steps_per_frame) as f32 * h;
                steps = s.max_steps_per_frame;
            }
            let start_target = st.prev_target;
            if steps > 0 && measurable {
                let owner_moved = comp.translation - prev_owner;
                st.drift =
                    (owner_moved * s.owner_velocity_scale - (target - start_target)) / self.dt;
            }
            for k in 1..=steps {
                // Where this step ends between last frame (0) and this one (1): the target
                // moves linearly across the frame's steps.
                let w = if self.dt > 0.0 {
                    ((k as f32 * h - carried) / self.dt).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                let tgt = start_target.lerp(target, w);
                st.step_target = tgt;
                // Carried by the owner's motion over exactly this step (Unreal adds owner
                // velocity × step; measured as a displacement it stays consistent with the
                // target when a step spans two frames or a frame carries a teleport).
                let owner = prev_owner.lerp(comp.translation, w);
                st.location += (owner - st.step_owner) * s.owner_velocity_scale;
                st.step_owner = owner;
                if beyond_reset(s, tgt - st.location) {
                    st.location = tgt;
                    st.velocity = Vec3::ZERO;
                    self.state.resets += 1;
                }
                // Hooke spring with damping. Unreal integrates v += a·h, x += v·h (first
                // order: about ω·h/2 of phase error); the same forces in kick-drift-kick
                // form are second order at the same cost.
                let safety = if s.damping > s.cutoff_damping {
                    s.cutoff_damping / s.damping
                } else {
                    1.0
                };
                let accel = |x: Vec3, v: Vec3| (tgt - x) * s.stiffness - v * s.damping;
                let v_half = st.velocity + accel(st.location, st.velocity) * (0.5 * h * safety);
                st.location += v_half * h;
                st.velocity = v_half + accel(st.location, v_half) * (0.5 * h * safety);
                if s.limit_displacement > 0.0 {
                    let d = st.location - tgt;
                    if d.length() > s.limit_displacement {
                        st.location = tgt + d.normalize() * s.limit_displacement;
                    }
                }
            }
            st.remaining -= steps as f32 * h;
            st.prev_target = target;
            // Output at this frame's time: this frame's target plus the last step's
            // deviation moved on by the carried-over time, within the displacement limit.
            let mut disp_ws = st.deviation();
            if beyond_reset(s, disp_ws) {
                // The output is held to the error reset too: a target that jumped within
                // the carried time (an animated bone thrown 1e6 m for one frame) must not
                // be extrapolated into a swing (found by the simulation fuzzer).
                st.initialized = false;
                self.state.resets += 1;
                disp_ws = Vec3::ZERO;
            }
            if !disp_ws.is_finite() {
                // Beyond f32: start again at the target. Validation refuses the settings
                // that overflow (see `SpringSettings::step_growth`); this stays as the
                // last guard so that no NaN is ever written.
                st.initialized = false;
                disp_ws = Vec3::ZERO;
            }
            if s.limit_displacement > 0.0 && disp_ws.length() > s.limit_displacement {
                disp_ws = disp_ws.normalize() * s.limit_displacement;
            }
            let mut disp_cs = inv_rot * disp_ws;
            for (axis, on) in s.translate.iter().enumerate() {
                if !on {
                    disp_cs[axis] = 0.0;
                }
            }
            let new_pos = self.models[j].translation + disp_cs;
            let mut rot = self.models[j].rotation;
            if let (true, Some(p)) = (s.use_rotation, self.skeleton.parent(j)) {
                let parent = self.models[p].translation;
                let swing = rotation_arc(
                    normalize_or(self.models[j].translation - parent, Vec3::Y),
                    normalize_or(new_pos - parent, Vec3::Y),
                );
                let (mut x, mut y, mut z) = swing.to_euler(EulerRot::XYZ);
                if !s.rotate[0] {
                    x = 0.0;
                }
                if !s.rotate[1] {
                    y = 0.0;
                }
                if !s.rotate[2] {
                    z = 0.0;
                }
                rot = (Quat::from_euler(EulerRot::XYZ, x, y, z) * rot).normalize();
            }
            let parent_model = self
                .skeleton
                .parent(j)
                .map(|p| self.models[p])
                .unwrap_or(Transform::IDENTITY);
            let model = Transform::new(new_pos, rot, self.models[j].scale);
            self.locals[j] = model.relative_to(&parent_model);
            self.models[j] = model;
        }
        crate::pose::LocalToModelJob {
            skeleton: self.skeleton,
            root: Transform::IDENTITY,
            locals: self.locals,
            models: self.models,
        }
        .run()
    }
}
