//! What a chain in `fixed` mode outputs (issue 63): its points at the frame's end. A frame
//! that ends on a step outputs that step's points; a frame between steps one more step of
//! the time left over, from the last step's state, not kept.
//!
//! - The output is never inside a collider, at 30, 60, 144 and 200 frames a second, with
//!   colliders on a bone swung at up to 24 rad/s through the chain (6 m/s at the
//!   shapes), the character shaken too; with the chain's alpha 1 and 0.8, and two chains
//!   joined by bone constraints (the group's step).
//! - The output between steps joins the steps: a frame that stops just short of a step's
//!   end outputs (nearly) the points that step gives, and a frame just after a step's
//!   end (nearly) that step's points.

use glam::{Quat, Vec3};
use tassel::collide::Shape;
use tassel::dynamics::chain::{
    BoneConstraintSettings, ChainJob, ChainRig, ChainSettings, ChainState, TimeMode,
};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{Pose, Skeleton, Transform};

const LINKS: usize = 6;
const LINK: f32 = 0.08;

/// A root with three children: `anchor`, from which a chain of [`LINKS`] bones hangs
/// along −Y; `anchor2`, 6 cm along X, with a second such chain; and `bat`, beside them,
/// which the animation swings.
fn skeleton() -> Skeleton {
    let mut names = vec!["root".to_string()];
    let mut parents = vec![None];
    let mut rest = vec![Transform::IDENTITY];
    for (anchor, at, bone) in [("anchor", 0.0, "b"), ("anchor2", 0.06, "c")] {
        names.push(anchor.into());
        parents.push(Some(0));
        rest.push(Transform::from_translation(Vec3::new(at, 0.0, 0.0)));
        for i in 0..LINKS {
            names.push(format!("{bone}{i}"));
            parents.push(Some(names.len() - 2));
            rest.push(Transform::from_translation(Vec3::new(0.0, -LINK, 0.0)));
        }
    }
    names.push("bat".into());
    parents.push(Some(0));
    rest.push(Transform::from_translation(Vec3::new(0.0, -0.25, 0.1)));
    Skeleton::new(names, parents, rest).unwrap()
}

/// The rig: chain `c` alone, or (`joined`) chains `c` and `d` side by side with a bone
/// constraint between each pair of their bones (one group: the scalar group step).
fn rig(alpha: f32, joined: bool) -> RigSettings {
    let mut chains = vec![chain(alpha)];
    let mut bone_constraints = Vec::new();
    if joined {
        chains.push(ChainSettings {
            name: "d".into(),
            root: "anchor2".into(),
            ..chain(alpha)
        });
        bone_constraints = (0..LINKS)
            .map(|i| BoneConstraintSettings {
                bone1: format!("b{i}"),
                bone2: format!("c{i}"),
                ..Default::default()
            })
            .collect();
    }
    RigSettings {
        chains,
        colliders: colliders(),
        bone_constraints,
        ..Default::default()
    }
}

fn chain(alpha: f32) -> ChainSettings {
    ChainSettings {
        name: "c".into(),
        root: "anchor".into(),
        damping: 0.05,
        stiffness: 0.05,
        radius: 0.02,
        alpha,
        mode: TimeMode::Fixed,
        target_framerate: 60.0,
        ..Default::default()
    }
}

fn on_bat(name: &str, offset: Vec3, shape: Shape) -> ColliderSettings {
    ColliderSettings {
        mirror: None,
        mirror_bone: String::new(),
        name: name.into(),
        bone: "bat".into(),
        offset,
        rotation: Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
        shape,
    }
}

/// Colliders the bat carries through the chain's plane, apart from each other.
fn colliders() -> Vec<ColliderSettings> {
    vec![
        on_bat(
            "ball",
            Vec3::new(0.25, 0.0, -0.1),
            Shape::Sphere {
                radius: 0.06,
                inside: false,
            },
        ),
        on_bat(
            "club",
            Vec3::new(-0.25, 0.0, -0.1),
            Shape::Capsule {
                radius: 0.04,
                length: 0.12,
            },
        ),
        on_bat(
            "cone",
            Vec3::new(0.0, 0.25, -0.1),
            Shape::TaperedCapsule {
                radius0: 0.05,
                radius1: 0.02,
                length: 0.1,
            },
        ),
    ]
}

/// The bat's swing about the character's Z axis (amplitude 1.5 rad at 2.5 Hz: up to
/// 23.6 rad/s) and the character's shake at time `t`.
fn animation(t: f32) -> (Quat, Transform) {
    let swing = 1.5 * (std::f32::consts::TAU * 2.5 * t).sin();
    let comp = Transform::from_translation_rotation(
        Vec3::new(0.3 * (9.0 * t).sin(), 0.2 * (7.0 * t).cos(), 0.0),
        Quat::from_rotation_z(0.3 * (5.0 * t).sin()),
    );
    (Quat::from_rotation_z(swing), comp)
}

struct Sim {
    sk: Skeleton,
    rig: ChainRig,
    state: ChainState,
}

impl Sim {
    fn new(alpha: f32, joined: bool) -> Sim {
        let sk = skeleton();
        let rig = ChainRig::new(&sk, &rig(alpha, joined)).unwrap();
        let state = ChainState::new(&rig);
        Sim { sk, rig, state }
    }

    /// One frame of `dt` ending at time `t`, the bat swung and the character shaken as
    /// [`animation`] gives them.
    fn frame(&mut self, t: f32, dt: f32) {
        let (bat, comp) = animation(t);
        let mut pose = Pose::rest(&self.sk);
        let b = self.sk.find("bat").unwrap();
        pose.locals[b].rotation = bat;
        pose.update_models(&self.sk, &Transform::IDENTITY).unwrap();
        let Pose {
            mut locals,
            mut models,
        } = pose;
        ChainJob {
            skeleton: &self.sk,
            rig: &self.rig,
            state: &mut self.state,
            component: comp,
            dt,
            locals: &mut locals,
            models: &mut models,
            level: None,
        }
        .run()
        .unwrap();
    }

    /// The deepest any output point is inside any of this frame's colliders (negative:
    /// the nearest is that far outside).
    fn deepest(&self) -> f32 {
        let out = self.state.output_positions();
        let mut worst = f32::MIN;
        for (p, &x) in out.iter().enumerate() {
            if self.rig.point(p).parent.is_none() {
                continue;
            }
            for c in self.state.placed_colliders() {
                worst = worst.max(c.penetration(x, self.rig.point_radius(p)));
            }
        }
        worst
    }
}

#[test]
fn fixed_output_is_never_inside_fast_colliders_at_any_frame_rate() {
    for (alpha, joined) in [(1.0, false), (0.8, false), (1.0, true)] {
        for hz in [30u32, 60, 144, 200] {
            let mut sim = Sim::new(alpha, joined);
            let (mut worst, mut touching) = (f32::MIN, 0);
            let frames = 4 * hz;
            for f in 0..=frames {
                let dt = if f == 0 { 0.0 } else { 1.0 / hz as f32 };
                sim.frame(f as f32 / hz as f32, dt);
                let d = sim.deepest();
                worst = worst.max(d);
                touching += usize::from(d > -2e-3);
            }
            let case = format!("alpha {alpha}, joined {joined}, {hz} Hz");
            println!("{case}: deepest {worst:.2e} m, {touching} of {frames} frames touching");
            assert!(
                worst <= 1e-4,
                "{case}: an output point {worst} m inside a collider"
            );
            // The colliders do reach the chain (else the test shows nothing).
            assert!(
                touching * 10 > frames as usize,
                "{case}: the chain touched in {touching} of {frames} frames"
            );
        }
    }
}

/// Two simulations take the same 60 Hz frames (one step each) to time `t`; then one
/// takes a frame of a step less `gap`, the other a whole step. As `gap` falls to 0 the
/// first's output (the output step of what is left) must reach the second's (a real
/// step): the largest point distance falls with `gap`, under 2 % of the step's largest
/// point motion at `gap` = 1 % of a step. Likewise a frame of `gap` after the step's end
/// outputs nearly the step's points.
#[test]
fn fixed_output_between_steps_joins_the_steps() {
    for joined in [false, true] {
        joins(joined);
    }
}

fn joins(joined: bool) {
    let h = 1.0 / 60.0;
    let mut reference = Sim::new(1.0, joined);
    reference.frame(0.0, 0.0);
    for f in 1..=40 {
        reference.frame(f as f32 * h, h);
    }
    let t = 40.0 * h;
    let largest = |a: &[Vec3], b: &[Vec3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.distance(*y))
            .fold(0.0f32, f32::max)
    };
    let before = reference.state.output_positions().to_vec();
    let mut whole = reference.clone_sim();
    whole.frame(t + h, h);
    let after = whole.state.output_positions().to_vec();
    let step = largest(&before, &after);
    assert!(step > 1e-3, "the chain barely moves in a step: {step} m");
    let mut last = (f32::MAX, f32::MAX);
    for gap in [0.3, 0.1, 0.03, 0.01] {
        // Short of the step's end: the output step of (1 − gap) of a step.
        let mut short = reference.clone_sim();
        short.frame(t + h * (1.0 - gap), h * (1.0 - gap));
        let d = largest(short.state.output_positions(), &after);
        // Past the step's end: the step, then the output step of `gap`.
        let mut past = whole.clone_sim();
        past.frame(t + h * (1.0 + gap), h * gap);
        let e = largest(past.state.output_positions(), &after);
        println!(
            "joined {joined}, gap {gap}: {:.3} / {:.3} mm from the step's points (the step moves them {:.1} mm)",
            1e3 * d,
            1e3 * e,
            1e3 * step
        );
        assert!(d < last.0, "gap {gap}: {d} m, not nearer than {} m", last.0);
        assert!(
            e < last.1,
            "gap {gap} past: {e} m, not nearer than {} m",
            last.1
        );
        last = (d, e);
        if gap == 0.01 {
            assert!(d < 0.02 * step, "gap {gap}: {d} m of a {step} m step");
            assert!(e < 0.02 * step, "gap {gap} past: {e} m of a {step} m step");
        }
    }
}

impl Sim {
    fn clone_sim(&self) -> Sim {
        Sim {
            sk: self.sk.clone(),
            rig: self.rig.clone(),
            state: self.state.clone(),
        }
    }
}

/// Between steps the output is about as smooth as the steps: the built-in character's
/// chains (its ponytail, tail and two locks, `fixed`), swayed ±0.3 m along X at 1 and
/// 2 Hz, rendered at 144 Hz (2.4 frames a step, most frames between steps); the RMS
/// over the chains' points of their frame-to-frame second difference after the first
/// second, against the 60 Hz run's (a step a frame) scaled to 144 Hz frames. Measured
/// 1.11× (1 Hz) and 1.21× (2 Hz); the blend of the last two steps this output replaced
/// gave 1.16× and 1.27× here.
#[test]
fn fixed_output_between_steps_is_about_as_smooth_as_the_steps() {
    use tassel::builtin;
    use tassel::CharacterSim;
    for freq in [1.0f32, 2.0] {
        let roughness = |hz: f32| {
            let c = builtin::character();
            let mut rig = c.rig.clone();
            for chain in &mut rig.chains {
                chain.mode = TimeMode::Fixed;
            }
            let mut sim = CharacterSim::new(c.skeleton.clone(), &rig).unwrap();
            let rest = c.skeleton.rest().to_vec();
            let mut frames: Vec<Vec<Vec3>> = Vec::new();
            for f in 0..=(5.0 * hz) as usize {
                let w = std::f32::consts::TAU * freq * f as f32 / hz;
                let comp = Transform::from_translation(Vec3::new(0.3 * w.sin(), 0.0, 0.0));
                sim.frame(&rest, comp, if f == 0 { 0.0 } else { 1.0 / hz })
                    .unwrap();
                let points = sim.chain_state().output_positions();
                frames.push(points.iter().map(|&p| comp.transform_point(p)).collect());
            }
            let (mut sum, mut n) = (0.0f64, 0usize);
            for i in hz as usize..frames.len() - 1 {
                for p in 0..frames[i].len() {
                    let d = frames[i + 1][p] - 2.0 * frames[i][p] + frames[i - 1][p];
                    sum += d.length_squared() as f64;
                    n += 1;
                }
            }
            (sum / n as f64).sqrt() as f32
        };
        let steps = roughness(60.0) * (60.0f32 / 144.0).powi(2);
        let output = roughness(144.0);
        println!(
            "{freq} Hz sway: 144 Hz output {:.3} mm, the steps' own {:.3} mm ({:.2}x)",
            output * 1e3,
            steps * 1e3,
            output / steps
        );
        assert!(output <= 1.3 * steps, "{freq} Hz: {output} against {steps}");
    }
}
