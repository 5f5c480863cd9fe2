//! Ropes on bones: a chain of bones driven by the particle world (seed 001). The root
//! bone's particle is attached to the animated root; every other bone is a free particle
//! tied to its parent by a stick; ground and body colliders act on them; the bones turn
//! toward the simulated particles. A `[[rope]]` table of the rig file.

use crate::dynamics::particles::{ParticleSettings, ParticleWorld};
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

/// Every rope of a rig with its particle world: compile once per character.
#[derive(Debug, Clone, Default)]
pub struct Ropes {
    ropes: Vec<CompiledRope>,
    worlds: Vec<ParticleWorld>,
    fresh: Vec<bool>,
    prev_component: Transform,
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
            world.attach(ids[0], bones[0], Vec3::ZERO)?;
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

    /// Rope `i`'s particle world (world-space positions, one particle per bone).
    pub fn world(&self, i: usize) -> &ParticleWorld {
        &self.worlds[i]
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

    /// One frame: moves the attachments and colliders to the pose (`models`, character
    /// space) at `component`, steps the worlds by `dt`, turns the bones toward the
    /// particles (writing `locals` and `models`).
    pub fn frame(
        &mut self,
        skeleton: &Skeleton,
        component: &Transform,
        dt: f32,
        locals: &mut [Transform],
        models: &mut [Transform],
    ) -> Result<()> {
        if self.ropes.is_empty() {
            return Ok(());
        }
        let moved = (component.translation - self.prev_component.translation).length();
        self.prev_component = *component;
        let frame = Transform::from_translation_rotation(component.translation, component.rotation);
        for (i, rope) in self.ropes.iter().enumerate() {
            let world = &mut self.worlds[i];
            let s = &rope.settings;
            if !self.fresh[i] && s.teleport_distance > 0.0 && moved > s.teleport_distance {
                self.fresh[i] = true;
                self.resets += 1;
            }
            if self.fresh[i] {
                for (k, &b) in rope.bones.iter().enumerate() {
                    world.set_position(k, frame.transform_point(models[b].translation));
                }
                self.fresh[i] = false;
            }
            world.colliders.clear();
            for c in &rope.colliders {
                world.colliders.push(c.place(models, Some(&frame)));
            }
            if let Some(h) = s.ground {
                world.add_ground(h);
            }
            world.follow_bones(models, &frame)?;
            world.step(dt)?;
            // Write-back: each bone turns so its child bone points at the child particle;
            // directions come from the animated models (positions are not updated until
            // the pose job at the end), rotations on top of the animated ones.
            let inv = frame.inverse();
            for k in 0..rope.bones.len() - 1 {
                let (j, c) = (rope.bones[k], rope.bones[k + 1]);
                let anim = models[c].translation - models[j].translation;
                let a = inv.transform_point(world.position(k));
                let b = inv.transform_point(world.position(k + 1));
                let sim = b - a;
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
