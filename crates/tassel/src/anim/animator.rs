//! The animation side of a frame: a state machine's plan sampled and blended into a pose.

use super::blend::{BlendJob, BlendLayer};
use super::clip::Clip;
use super::root_motion::RootMotion;
use super::sample::{Playback, SamplingCursor, SamplingJob};
use super::state_machine::{BlendPlan, StateMachine, StateMachineState};
use crate::error::Result;
use crate::math::Transform;
use glam::Vec3;

/// Runs a [`StateMachine`] over a set of clips and produces the blended local pose.
///
/// Buffers grow to the largest plan seen and are then reused: steady play allocates
/// nothing.
#[derive(Debug, Clone)]
pub struct Animator {
    machine: StateMachine,
    /// The machine's per-character state: set parameters through it.
    pub state: StateMachineState,
    plan: BlendPlan,
    cursors: Vec<SamplingCursor>,
    buffers: Vec<Vec<Transform>>,
    /// When set, the horizontal travel of this joint is taken out of the pose and
    /// reported by [`Animator::root_motion_delta`] for the character controller.
    pub root_motion: Option<RootMotion>,
    delta: Vec3,
}

impl Animator {
    /// An animator for `clips` driven by `machine` (compiled for the same clips).
    pub fn new(machine: StateMachine, clips: &[Clip]) -> Self {
        let state = machine.new_state();
        Self {
            machine,
            state,
            plan: BlendPlan::default(),
            cursors: clips.iter().map(SamplingCursor::new).collect(),
            buffers: Vec::new(),
            root_motion: None,
            delta: Vec3::ZERO,
        }
    }

    /// The root's horizontal travel during the last update (parent space of the root
    /// joint), blended with the layers' weights; zero without [`Animator::root_motion`].
    pub fn root_motion_delta(&self) -> Vec3 {
        self.delta
    }

    /// The state machine.
    pub fn machine(&self) -> &StateMachine {
        &self.machine
    }

    /// Advances by `dt`, samples every layer of the plan and blends them into `out`
    /// (`rest` fills joints no clip animates). Returns the plan (states, weights, events).
    pub fn update(
        &mut self,
        clips: &[Clip],
        rest: &[Transform],
        dt: f32,
        out: &mut [Transform],
    ) -> Result<&BlendPlan> {
        self.machine.update(&mut self.state, dt, &mut self.plan);
        while self.buffers.len() < self.plan.layers.len() {
            self.buffers.push(rest.to_vec());
        }
        self.delta = Vec3::ZERO;
        for (layer, buf) in self.plan.layers.iter().zip(self.buffers.iter_mut()) {
            if let Some(rm) = &self.root_motion {
                let clip = &clips[layer.clip];
                let t0 = layer.time - layer.rate * dt;
                self.delta += rm.delta(clip, t0, layer.time, layer.looping) * layer.weight;
            }
            buf.resize(rest.len(), Transform::IDENTITY);
            buf.copy_from_slice(rest);
            SamplingJob {
                clip: &clips[layer.clip],
                cursor: &mut self.cursors[layer.clip],
                time: layer.time,
                playback: Playback::Clamp,
                locals: buf,
            }
            .run()?;
            if let Some(rm) = &self.root_motion {
                rm.strip(&clips[layer.clip], buf);
            }
        }
        let mut layers = [BlendLayer {
            locals: rest,
            weight: 0.0,
            mask: None,
        }; 8];
        let n = self.plan.layers.len().min(layers.len());
        for k in 0..n {
            layers[k] = BlendLayer {
                locals: &self.buffers[k],
                weight: self.plan.layers[k].weight,
                mask: None,
            };
        }
        BlendJob {
            rest,
            layers: &layers[..n],
            additive: &[],
            out,
        }
        .run()?;
        Ok(&self.plan)
    }
}
