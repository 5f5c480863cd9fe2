//! `tassel bench`: ns per joint-step for a synthetic character, single thread.

use std::time::Instant;
use tassel::collide::Shape;
use tassel::dynamics::vrm::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmMode, VrmOptions, VrmShape, VrmSpring,
    VrmSpringBones, VrmTail,
};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, Transform};

/// Options of `tassel bench`.
#[derive(clap::Args)]
pub struct Args {
    /// Frames per measurement.
    #[arg(long, default_value_t = 2000)]
    frames: usize,
    /// Measurements (the median is reported).
    #[arg(long, default_value_t = 11)]
    runs: usize,
    /// Run the same joints and colliders as VRM spring bones in this mode instead of
    /// chains.
    #[arg(long, value_enum)]
    vrm: Option<VrmBenchMode>,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum VrmBenchMode {
    Spec,
    Fixed,
    ThreeVrm,
}

/// The bench rig's chains and colliders as VRM springs: every non-root chain bone swings
/// toward its child (the last one toward a virtual tail), colliding with all colliders.
fn as_vrm(sk: &Skeleton, rig: &RigSettings) -> VrmSpringBones {
    let mut b = VrmSpringBones::default();
    for c in &rig.colliders {
        let joint = sk.find(&c.bone).expect("bench collider bone");
        let shape = match c.shape {
            Shape::Sphere { radius, inside } => VrmShape::Sphere {
                offset: c.offset,
                radius,
                inside,
            },
            Shape::Capsule { radius, length } => {
                let axis = c.rotation * glam::Vec3::Y * (0.5 * length);
                VrmShape::Capsule {
                    offset: c.offset - axis,
                    tail: c.offset + axis,
                    radius,
                    inside: false,
                }
            }
            _ => continue,
        };
        b.colliders.push(VrmCollider { joint, shape });
    }
    b.collider_groups.push(VrmColliderGroup {
        name: "all".into(),
        colliders: (0..b.colliders.len()).collect(),
    });
    for ch in &rig.chains {
        let root = sk.find(&ch.root).expect("bench chain root");
        let mut joints = Vec::new();
        let mut j = sk.children(root).next();
        while let Some(k) = j {
            let child = sk.children(k).next();
            joints.push(VrmJoint {
                joint: k,
                tail: match child {
                    Some(c) => VrmTail::Joint(c),
                    None => VrmTail::Local(glam::Vec3::new(0.0, -0.07, 0.0)),
                },
                hit_radius: 0.02,
                stiffness: 1.0,
                gravity_power: 1.0,
                ..Default::default()
            });
            j = child;
        }
        b.springs.push(VrmSpring {
            name: ch.name.clone(),
            joints,
            collider_groups: vec![0],
            center: None,
        });
    }
    b
}

pub fn run(a: Args) -> Result<(), String> {
    let (chains, joints, colliders) = (16, 8, 8);
    let (sk, rig) = builtin::bench_character(chains, joints, colliders);
    let (mut sim, simulated, what) = match a.vrm {
        None => {
            let sim = CharacterSim::new(sk.clone(), &rig).map_err(|e| e.to_string())?;
            let simulated = sim.chains().point_count() - chains; // roots are not simulated
            (
                sim,
                simulated,
                "chains, fixed mode 60 Hz, one step per frame".to_string(),
            )
        }
        Some(m) => {
            let bones = as_vrm(&sk, &rig);
            let mode = match m {
                VrmBenchMode::Spec => VrmMode::Spec,
                VrmBenchMode::Fixed => VrmMode::Fixed,
                VrmBenchMode::ThreeVrm => VrmMode::ThreeVrm,
            };
            let options = VrmOptions {
                mode,
                ..Default::default()
            };
            let sim = CharacterSim::with_vrm(sk.clone(), &RigSettings::default(), &bones, options)
                .map_err(|e| e.to_string())?;
            let simulated = sim.vrm().links.len();
            (
                sim,
                simulated,
                format!("VRM spring bones, {mode:?} mode, 60 Hz frames"),
            )
        }
    };
    let rest = sk.rest().to_vec();
    let dt = 1.0 / 60.0;
    let mut f = 0usize;
    let mut one_run = |frames: usize| -> Result<f64, String> {
        let start = Instant::now();
        for _ in 0..frames {
            f += 1;
            let t = f as f32 * dt;
            let comp = Transform::from_translation(glam::Vec3::new((3.0 * t).sin() * 0.5, 0.0, t));
            sim.frame(&rest, comp, dt).map_err(|e| e.to_string())?;
        }
        Ok(start.elapsed().as_nanos() as f64 / (frames * simulated) as f64)
    };
    one_run(a.frames / 4 + 1)?; // warm up
    let mut samples = Vec::new();
    for _ in 0..a.runs.max(1) {
        samples.push(one_run(a.frames.max(1))?);
    }
    samples.sort_by(|x, y| x.total_cmp(y));
    let median = samples[samples.len() / 2];
    say!("tassel bench: {chains} chains x {joints} joints, {colliders} colliders, {what}, single thread");
    say!(
        "  {simulated} simulated joints; median of {} runs x {} frames",
        samples.len(),
        a.frames
    );
    say!(
        "  {median:.1} ns per joint-step (frame incl. pose jobs and write-back: {:.2} us)",
        median * simulated as f64 / 1000.0
    );
    say!(
        "  min {:.1}  max {:.1} ns per joint-step",
        samples[0],
        samples[samples.len() - 1]
    );
    Ok(())
}
