//! One frame of every bound character: read the animated bone `Transform`s, step, write
//! the simulated bones back (before Bevy propagates transforms).
//!
//! Three passes, all on Bevy's compute task pool. **Read**: each character's animated
//! bones and its world transform into its input buffer (its own, or its slot of its
//! kind's crowd: `Kind::read`, members shared out over the pool). **Step**: every crowd
//! (SIMD lanes, its lane groups shared out with `frame_parts`), and the characters on
//! their own `CharacterSim` in parallel. **Write**: each character's simulated bones back
//! to their entities (`Kind::write` for crowds, shared out too). Only the bones a solver
//! reads or writes are touched; the characters on their own sims are read and written
//! one after another.

use crate::character::TasselCharacter;
use crate::convert::{to_bevy, to_tassel, world_of};
use crate::crowd::Crowds;
use crate::crowd_bones::{CrowdBone, WrittenBone};
use crate::TasselError;
use bevy::diagnostic::{Diagnostic, DiagnosticPath, Diagnostics};
use bevy::ecs::prelude::*;
use bevy::log::warn;
use bevy::prelude::{ChildOf, Transform};
use bevy::time::Time;
use std::time::Instant;

/// The plugin's time per frame in [`TasselSystems::Step`](crate::TasselSystems::Step)
/// (reading, stepping and writing every character), milliseconds: a diagnostic in Bevy's
/// `DiagnosticsStore`.
pub const STEP_TIME: DiagnosticPath = DiagnosticPath::const_new("tassel/step_ms");

/// The part of [`STEP_TIME`] spent reading the animated bones (and character roots)
/// into the solvers' input buffers, milliseconds.
pub const READ_TIME: DiagnosticPath = DiagnosticPath::const_new("tassel/read_ms");

/// The part of [`STEP_TIME`] spent in the solvers (every crowd and every character on
/// its own simulation), milliseconds.
pub const SOLVE_TIME: DiagnosticPath = DiagnosticPath::const_new("tassel/solve_ms");

/// The part of [`STEP_TIME`] spent writing the simulated bones' `Transform`s,
/// milliseconds.
pub const WRITE_TIME: DiagnosticPath = DiagnosticPath::const_new("tassel/write_ms");

/// The step's diagnostics, registered with their unit.
pub(crate) fn step_time_diagnostics() -> [Diagnostic; 4] {
    [STEP_TIME, READ_TIME, SOLVE_TIME, WRITE_TIME].map(|p| Diagnostic::new(p).with_suffix(" ms"))
}

/// Reads character `c`'s animated pose into `locals`: every bone's Transform as the
/// animation left it. A simulated bone that still holds what the plugin wrote last frame
/// was not animated since (no clip drives it): it keeps its last animated pose. A bone
/// without an entity stays at rest. (Crowd members are read by their kind:
/// `Kind::read`.)
fn read_pose(
    c: &TasselCharacter,
    locals: &mut [tassel::Transform],
    transforms: &Query<&Transform>,
) {
    let mut read = |j: usize, mine: Option<tassel::Transform>| {
        if let Some(t) = c.bones[j].and_then(|e| transforms.get(e).ok()) {
            let t = to_tassel(t);
            if mine != Some(t) {
                locals[j] = t;
            }
        }
    };
    // `written` is ascending by joint, as `0..n` is: one merge walk.
    let mut w = 0;
    let mut mine = |j: usize| {
        while c.written.get(w).is_some_and(|&(k, _)| k < j) {
            w += 1;
        }
        match c.written.get(w) {
            Some(&(k, _)) if k == j => c.wrote[w],
            _ => None,
        }
    };
    (0..c.bones.len()).for_each(|j| read(j, mine(j)));
}

/// Writes the simulated joints of `pose` to character `c`'s bones.
fn write_pose(
    c: &mut TasselCharacter,
    pose: &[tassel::Transform],
    transforms: &mut Query<&mut Transform>,
) {
    for (&(j, e), wrote) in c.written.iter().zip(&mut c.wrote) {
        if let Ok(mut t) = transforms.get_mut(e) {
            *t = to_bevy(&pose[j]);
            *wrote = Some(pose[j]);
        }
    }
}

/// Reports a frame error once until it changes; the bones keep their animated pose.
fn report(
    entity: Entity,
    c: &mut TasselCharacter,
    message: String,
    errors: &mut MessageWriter<TasselError>,
) {
    if c.last_error.as_deref() != Some(message.as_str()) {
        warn!("tassel: entity {entity}: frame skipped: {message}");
        errors.write(TasselError {
            entity,
            message: message.clone(),
        });
        c.last_error = Some(message);
    }
}

/// Every `Transform` (looked up by entity), the crowd members' tagged bones whose
/// `Transform` changed since the step last ran (read), and the tagged bones (written).
type Transforms<'w, 's> = ParamSet<
    'w,
    's,
    (
        Query<'static, 'static, &'static mut Transform>,
        Query<'static, 'static, (&'static CrowdBone, &'static Transform), Changed<Transform>>,
        Query<'static, 'static, (&'static CrowdBone, &'static mut Transform), With<WrittenBone>>,
    ),
>;

#[allow(clippy::too_many_arguments)]
pub(crate) fn step_characters(
    time: Res<Time>,
    mut commands: Commands,
    mut characters: Query<(Entity, &mut TasselCharacter)>,
    mut transforms: Transforms,
    parents: Query<&ChildOf>,
    mut errors: MessageWriter<TasselError>,
    mut crowds: ResMut<Crowds>,
    mut removed: RemovedComponents<TasselCharacter>,
    mut held: Local<Vec<(usize, tassel::Error)>>,
    mut diagnostics: Diagnostics,
) {
    let started = Instant::now();
    let dt = time.delta_secs();
    let crowds = &mut *crowds;
    // Characters gone (despawned, or rebound with another rig or mode) leave their crowd;
    // the member that takes a leaver's index follows it.
    for entity in removed.read() {
        if let Some((moved, i)) = crowds.leave(entity, &mut commands) {
            if let Ok((_, mut c)) = characters.get_mut(moved) {
                c.slot = Some(i);
            }
        }
    }
    // New crowd members join (a character whose kind runs as a crowd has no sim of its
    // own: bind left it `None`); a member whose solvers start again (first frame, reset,
    // teleport) tells its crowd.
    for (entity, mut c) in &mut characters {
        if c.sim.is_none() && c.slot.is_none() {
            let rig = c.rig.clone();
            match crowds.join(entity, &rig, &c.bones, c.space, &mut commands) {
                Some(i) => c.slot = Some(i),
                // Not a crowd after all (its crowd failed to build): its own sim.
                None => c.sim = Some(tassel::CharacterSim::from_rig(rig)),
            }
        }
        if c.first_frame && c.slot.is_some() {
            if let Some((kind, i)) = crowds.kind_of(entity) {
                kind.reset(i);
            }
            c.first_frame = false;
        }
    }
    // Read: the characters on their own sims, then every crowd's members (in parallel).
    {
        let transforms = transforms.p0();
        let transforms = transforms.as_readonly();
        for (_, mut c) in &mut characters {
            if c.sim.is_none() {
                continue;
            }
            let c = &mut *c;
            c.root = world_of(c.space, &transforms, &parents);
            let mut locals = std::mem::take(&mut c.locals);
            read_pose(c, &mut locals, &transforms);
            c.locals = locals;
        }
        for kind in crowds.kinds.values_mut() {
            kind.read(&transforms, &parents);
        }
    }
    crowds.read_tagged(&transforms.p1());
    let read = Instant::now();
    // Step: the characters on their own sims in parallel, then each crowd (its lane
    // groups in parallel), all on Bevy's compute task pool.
    characters.par_iter_mut().for_each(|(_, mut c)| {
        let c = &mut *c;
        let Some(sim) = c.sim.as_mut() else {
            return;
        };
        let dt = if c.first_frame {
            sim.reset();
            0.0
        } else {
            dt
        };
        c.result = sim
            .frame(&c.locals, c.root, dt)
            .err()
            .map(|e| e.to_string());
        if c.result.is_none() {
            c.first_frame = false;
        }
    });
    for kind in crowds.kinds.values_mut() {
        kind.frame(dt, &mut held);
        for (i, e) in held.drain(..) {
            let entity = kind.members[i];
            if let Ok((_, mut c)) = characters.get_mut(entity) {
                c.result = Some(e.to_string());
            }
        }
    }
    let solved = Instant::now();
    // Write: every crowd's members, then the characters on their own sims; errors.
    for kind in crowds.kinds.values_mut() {
        kind.write(&mut transforms.p0());
    }
    crowds.write_tagged(&mut transforms.p2());
    for kind in crowds.kinds.values_mut() {
        kind.tags_arrived();
    }
    for (entity, mut c) in &mut characters {
        if c.result.is_none() && c.last_error.is_none() && c.sim.is_none() {
            continue;
        }
        let c = &mut *c;
        if let Some(message) = c.result.take() {
            report(entity, c, message, &mut errors);
            continue;
        }
        c.last_error = None;
        if let Some(sim) = c.sim.take() {
            write_pose(c, &sim.pose().locals, &mut transforms.p0());
            c.sim = Some(sim);
        }
    }
    let written = Instant::now();
    let ms = |a: Instant, b: Instant| b.duration_since(a).as_secs_f64() * 1e3;
    diagnostics.add_measurement(&STEP_TIME, || ms(started, written));
    diagnostics.add_measurement(&READ_TIME, || ms(started, read));
    diagnostics.add_measurement(&SOLVE_TIME, || ms(read, solved));
    diagnostics.add_measurement(&WRITE_TIME, || ms(solved, written));
}
