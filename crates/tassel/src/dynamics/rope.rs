//! Ropes on bones: a chain of bones driven by the particle world (seed 001). The root
//! bone's particle is pinned to the animated root; every other bone is a free particle
//! tied to its parent by a stick; ground, body colliders and (optionally) the world act on
//! them; the bones turn toward the simulated particles. Fixed steps with the pin and the
//! colliders interpolated between frames, output interpolated between the last two
//! steps. A `[[rope]]` table of the rig file.

use crate::collide::PlacedCollider;
use crate::controller::Level;
use crate::dynamics::particles::{ParticleSettings, ParticleWorld};
use crate::dynamics::path::CharacterPath;
use crate::dynamics::world::push_out;
use crate::dynamics::{CompiledCollider, RigSettings};
use crate::error::{Error, Result};
use crate::math::{rotation_arc, Transform};
use crate::skeleton::Skeleton;
use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// One rope (a `[[rope]]` table of the rig file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RopeSettings {
    /// A name for messages.
    pub name: String,
    /// First bone: follows the animation; the rope hangs from it.
    pub root: String,
    /// Last bone; the rope is it and its ancestors up to `root`.
    pub end: String,
    /// Mass of the whole rope, kg (> 0; only ratios matter without other bodies).
    pub mass: f32,
    /// Colliders (rig collider names; empty = all).
    pub colliders: Vec<String>,
    /// World height of a ground plane (none if absent).
    pub ground: Option<f32>,
    /// Reset when the character moves farther than this in one frame, metres (0 = never).
    pub teleport_distance: f32,
    /// Also keep every free particle `world.radius` out of the world: the `Level` given to
    /// `CharacterSim::set_level` (swept from where the step started, sliding, with
    /// `world.friction`).
    pub world_collision: bool,
    /// The particle world's parameters (gravity, damping, time step, iterations, radius,
    /// friction, wind, gusts).
    pub world: ParticleSettings,
}

impl Default for RopeSettings {
    fn default() -> Self {
        Self {
            name: String::new(),
            root: String::new(),
            end: String::new(),
            mass: 0.1,
            colliders: Vec::new(),
            ground: None,
            teleport_distance: 1.0,
            world_collision: false,
            world: ParticleSettings::default(),
        }
    }
}

impl RopeSettings {
    /// Checks every parameter; errors name the rope.
    pub fn validate(&self) -> Result<()> {
        let name = &self.name;
        self.world
            .validate()
            .map_err(|e| Error::InvalidParameter(format!("rope '{name}': {e}")))?;
        if !(self.mass.is_finite() && self.mass > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "rope '{name}': mass = {} must be finite and > 0",
                self.mass
            )));
        }
        if !(self.teleport_distance.is_finite() && self.teleport_distance >= 0.0) {
            return Err(Error::InvalidParameter(format!(
                "rope '{name}': teleport_distance = {} must be finite and ≥ 0",
                self.teleport_distance
            )));
        }
        if let Some(g) = self.ground {
            if !g.is_finite() {
                return Err(Error::InvalidParameter(format!(
                    "rope '{name}': ground = {g} is not finite"
                )));
            }
        }
        Ok(())
    }
}

#[derive(Debug, Clone)]
struct CompiledRope {
    settings: RopeSettings,
    /// Bones from the root down.
    bones: Vec<usize>,
    colliders: Vec<CompiledCollider>,
}

/// What one rope carries from frame to frame besides its particle world (world space,
/// one entry per bone).
#[derive(Debug, Clone, Default)]
struct RopeState {
    /// This frame's animated bone positions.
    anim: Vec<Vec3>,
    /// The same in the character's space, now and at the last frame's end (the steps
    /// carry them along the character's path).
    model_anim: Vec<Vec3>,
    prev_model_anim: Vec<Vec3>,
    /// Colliders in the character's space, now and at the last frame's end.
    colliders_cs: Vec<PlacedCollider>,
    prev_colliders_cs: Vec<PlacedCollider>,
    /// Each particle's offset from the root particle after the last step and the one
    /// before it.
    dev: Vec<Vec3>,
    dev_before: Vec<Vec3>,
    /// The output: the interpolated offsets hung from this frame's animated root.
    out: Vec<Vec3>,
    /// This frame's colliders (world space), for the output.
    colliders: Vec<PlacedCollider>,
    /// Time not yet stepped, seconds (< one step).
    accumulator: f32,
}

/// Every rope of a rig with its particle world: compile once per character.
///
/// Each rope steps its world at the fixed `world.time_step` with the root bone's pin and
/// the colliders interpolated to each step's time, and shows the particles' offsets from
/// the root interpolated between the last two steps, hung from this frame's root, so that
/// the swing does not depend on the frame rate.
#[derive(Debug, Clone, Default)]
pub struct Ropes {
    ropes: Vec<CompiledRope>,
    worlds: Vec<ParticleWorld>,
    states: Vec<RopeState>,
    fresh: Vec<bool>,
    prev_component: Transform,
    /// The character's recent transforms: where it was at each step's time.
    path: CharacterPath,
    resets: u64,
}

impl Ropes {
    /// Compiles the `[[rope]]` tables of `rig` for `skeleton`.
    pub fn new(skeleton: &Skeleton, rig: &RigSettings) -> Result<Self> {
        let mut out = Ropes::default();
        if rig.ropes.is_empty() {
            return Ok(out);
        }
        rig.validate_for(skeleton)?;
        let rig = &*rig.mirrored(skeleton)?;
        let all = CompiledCollider::compile_all(skeleton, rig);
        for s in &rig.ropes {
            let missing = |n: &str| Error::MissingBone {
                context: format!("rope '{}'", s.name),
                name: n.to_string(),
            };
            let root = skeleton.find(&s.root).ok_or_else(|| missing(&s.root))?;
            let end = skeleton.find(&s.end).ok_or_else(|| missing(&s.end))?;
            let mut bones = vec![end];
            let mut j = end;
            while j != root {
                j = skeleton.parent(j).ok_or_else(|| {
                    Error::InvalidParameter(format!(
                        "rope '{}': bone '{}' is not below '{}'",
                        s.name, s.end, s.root
                    ))
                })?;
                bones.push(j);
            }
            bones.reverse();
            if bones.len() < 2 {
                return Err(Error::InvalidParameter(format!(
                    "rope '{}': needs at least two bones",
                    s.name
                )));
            }
            // In the rig's order, each once.
            let mut chosen = rig.collider_indices(&s.colliders);
            chosen.sort_unstable();
            chosen.dedup();
            let colliders: Vec<CompiledCollider> = chosen.iter().map(|&i| all[i].clone()).collect();
            let mut world = ParticleWorld::new(s.world.clone());
            let rest = crate::pose::Pose::rest(skeleton);
            let m = s.mass / bones.len() as f32;
            let ids: Vec<usize> = bones
                .iter()
                .map(|&b| world.add_particle(rest.models[b].translation, m))
                .collect();
            for w in ids.windows(2) {
                world.add_stick(w[0], w[1])?;
            }
            world.pin(ids[0], rest.models[bones[0]].translation)?;
            let n = bones.len();
            out.states.push(RopeState {
                anim: vec![Vec3::ZERO; n],
                model_anim: vec![Vec3::ZERO; n],
                prev_model_anim: vec![Vec3::ZERO; n],
                colliders_cs: Vec::with_capacity(colliders.len()),
                prev_colliders_cs: Vec::with_capacity(colliders.len()),
                dev: vec![Vec3::ZERO; n],
                dev_before: vec![Vec3::ZERO; n],
                out: vec![Vec3::ZERO; n],
                colliders: Vec::with_capacity(colliders.len()),
                accumulator: 0.0,
            });
            out.ropes.push(CompiledRope {
                settings: s.clone(),
                bones,
                colliders,
            });
            out.worlds.push(world);
            out.fresh.push(true);
        }
        Ok(out)
    }

    /// True without ropes.
    pub fn is_empty(&self) -> bool {
        self.ropes.is_empty()
    }

    /// Number of ropes.
    pub fn len(&self) -> usize {
        self.ropes.len()
    }

    /// The bones rope `i` moves (all but its root).
    pub fn simulated_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.ropes.iter().flat_map(|r| r.bones[1..].iter().copied())
    }

    /// The joints the ropes turn: every bone of a rope but the last (the first one, pinned
    /// to its animated place, included).
    pub fn turned_joints(&self) -> impl Iterator<Item = usize> + '_ {
        self.ropes
            .iter()
            .flat_map(|r| r.bones[..r.bones.len().saturating_sub(1)].iter().copied())
    }

    /// Rope `i`'s particle world (world-space positions after the last step, one particle
    /// per bone).
    pub fn world(&self, i: usize) -> &ParticleWorld {
        &self.worlds[i]
    }

    /// Rope `i`'s output positions of the last frame (world space, one per bone, root
    /// first): the particles' offsets from the root interpolated between the last two
    /// steps, hung from the animated root with the stick lengths, kept out of the
    /// colliders; the bones turn toward these.
    pub fn output_positions(&self, i: usize) -> &[Vec3] {
        &self.states[i].out
    }

    /// Rope `i`'s bones, root first (the root follows the animation; each further bone
    /// hangs from the one before it).
    pub fn bones(&self, i: usize) -> &[usize] {
        &self.ropes[i].bones
    }

    /// Rope `i`'s settings.
    pub fn settings(&self, i: usize) -> &RopeSettings {
        &self.ropes[i].settings
    }

    /// How many teleport resets happened.
    pub fn reset_count(&self) -> u64 {
        self.resets
    }

    /// Starts every rope again from the animated pose on the next frame.
    pub fn reset(&mut self) {
        self.fresh.iter_mut().for_each(|f| *f = true);
    }

    /// One frame: the animated pose (`models`, character space) at `component`; steps
    /// each rope's world at its fixed step with the root pin and the colliders
    /// interpolated from the last frame's, keeps the free particles out of `level` when
    /// the rope has `world_collision`, and turns the bones toward the output (writing
    /// `locals` and `models`).
    pub fn frame(
        &mut self,
        skeleton: &Skeleton,
        component: &Transform,
        dt: f32,
        locals: &mut [Transform],
        models: &mut [Transform],
        level: Option<&Level>,
    ) -> Result<()> {
        if self.ropes.is_empty() {
            return Ok(());
        }
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(Error::InvalidTimeStep(dt));
        }
        let moved = (component.translation - self.prev_component.translation).length();
        self.prev_component = *component;
        self.path.push(*component, dt);
        let frame = Transform::from_translation_rotation(component.translation, component.rotation);
        for (i, rope) in self.ropes.iter().enumerate() {
            let world = &mut self.worlds[i];
            let st = &mut self.states[i];
            let s = &rope.settings;
            world.settings.validate()?;
            for (k, &b) in rope.bones.iter().enumerate() {
                st.model_anim[k] = models[b].translation;
                st.anim[k] = frame.transform_point(models[b].translation);
            }
            st.colliders.clear();
            st.colliders_cs.clear();
            for c in &rope.colliders {
                st.colliders.push(c.place(models, Some(&frame)));
                st.colliders_cs.push(c.place(models, None));
            }
            if !self.fresh[i] && s.teleport_distance > 0.0 && moved > s.teleport_distance {
                self.fresh[i] = true;
                self.resets += 1;
            }
            if self.fresh[i] {
                for k in 0..rope.bones.len() {
                    world.set_position(k, st.anim[k]);
                }
                st.prev_model_anim.copy_from_slice(&st.model_anim);
                st.prev_colliders_cs.clone_from(&st.colliders_cs);
                for k in 0..rope.bones.len() {
                    st.dev[k] = st.anim[k] - st.anim[0];
                    st.dev_before[k] = st.dev[k];
                }
                st.accumulator = 0.0;
                self.fresh[i] = false;
                self.path.reset(*component);
            }
            let level = level.filter(|_| s.world_collision);
            let h = world.settings.time_step;
            let start = st.accumulator;
            let mut total = start + dt;
            let mut steps = (total / h + 1e-4).floor() as u32;
            if steps > world.settings.max_steps_per_frame {
                total -= (steps - world.settings.max_steps_per_frame) as f32 * h;
                steps = world.settings.max_steps_per_frame;
            }
            for n in 1..=steps {
                // Where this step's end lies in the frame: 0 = last frame's end, 1 = now.
                let w = ((n as f32 * h - start) / (total - start).max(h * 1e-3)).clamp(0.0, 1.0);
                // The root and the colliders (character space) interpolated to the step's
                // time, carried along the character's path.
                let comp = self.path.at(w);
                let root = st.prev_model_anim[0].lerp(st.model_anim[0], w);
                world.set_pin_target(0, comp.transform_point(root));
                world.colliders.clear();
                for (a, b) in st.prev_colliders_cs.iter().zip(&st.colliders_cs) {
                    let cs = a.lerp(b, w);
                    world.colliders.push(PlacedCollider {
                        shape: cs.shape,
                        transform: comp * cs.transform,
                    });
                }
                if let Some(g) = s.ground {
                    world.add_ground(g);
                }
                world.step_once(level);
                for k in 0..rope.bones.len() {
                    st.dev_before[k] = st.dev[k];
                    st.dev[k] = world.position(k) - world.position(0);
                }
            }
            st.accumulator = (total - steps as f32 * h).max(0.0);
            if (0..rope.bones.len()).any(|k| !world.position(k).is_finite()) {
                // Never let a non-finite value out: start again from the pose next frame.
                self.fresh[i] = true;
                self.resets += 1;
                for k in 0..rope.bones.len() {
                    st.dev[k] = st.anim[k] - st.anim[0];
                    st.dev_before[k] = st.dev[k];
                }
            }
            // Output: the offsets from the root interpolated between the last two steps,
            // hung from this frame's animated root, stick lengths restored from the root
            // down, then kept out of this frame's colliders and the world.
            let w = (st.accumulator / h).clamp(0.0, 1.0);
            let r = world.settings.radius;
            st.out[0] = st.anim[0];
            for k in 1..rope.bones.len() {
                let length = world.sticks()[k - 1].length;
                let x = st.anim[0] + st.dev_before[k].lerp(st.dev[k], w);
                let d = x - st.out[k - 1];
                let mut x = if d.length_squared() > 1e-18 {
                    st.out[k - 1] + d * (length / d.length())
                } else {
                    x
                };
                for c in &st.colliders {
                    x = c.resolve(x, x, r);
                }
                if let Some(g) = s.ground {
                    x.y = x.y.max(g + r);
                }
                if let Some(level) = level {
                    x = push_out(level, x, r);
                }
                st.out[k] = x;
            }
            st.prev_model_anim.copy_from_slice(&st.model_anim);
            std::mem::swap(&mut st.prev_colliders_cs, &mut st.colliders_cs);
            // Write-back: each bone turns so its child bone points at the child's output
            // position; directions come from the animated models (positions are not
            // updated until the pose job at the end), rotations on top of the animated ones.
            let inv = frame.inverse();
            for k in 0..rope.bones.len() - 1 {
                let (j, c) = (rope.bones[k], rope.bones[k + 1]);
                let anim = models[c].translation - models[j].translation;
                let sim = inv.transform_point(st.out[k + 1]) - inv.transform_point(st.out[k]);
                if anim.length_squared() < 1e-12 || sim.length_squared() < 1e-12 {
                    continue;
                }
                let new_rot = (rotation_arc(anim, sim) * models[j].rotation).normalize();
                let parent_rot = skeleton
                    .parent(j)
                    .map_or(Quat::IDENTITY, |q| models[q].rotation);
                locals[j].rotation = (parent_rot.inverse() * new_rot).normalize();
                models[j].rotation = new_rot;
            }
        }
        crate::pose::LocalToModelJob {
            skeleton,
            root: Transform::IDENTITY,
            locals,
            models,
        }
        .run()
    }
}
