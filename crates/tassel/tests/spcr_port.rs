//! The cloth's `spcr` mode against a float64 port of SPCRJointDynamicsUE4's update,
//! written from the plugin's source (`SPARK-inc/SPCRJointDynamicsUE4` at `af91cb1`,
//! `Plugins/5.4/Plugins/SPCRJointDynamics/Source/SPCRJointDynamics/Private/
//! AnimNode_SPCRJointDynamics.cpp`): `EvaluateSkeletalControl_AnyThread`,
//! `UpdateControlPoints`, `UpdateColliders`, `UpdateConstraints`, `UpdateCollision`,
//! `UpdateSurfaceCollision`, `UpdateLockAngles`, `ForceFixConstraints`, `ApplyToBone`, and
//! the `Create…` functions. The port works in metres (SPCR's centimetre tolerances
//! converted), keeps SPCR's time bookkeeping in f32 (its `float`), and skips a push where
//! SPCR would divide by zero (as the mode does, and as documented).
//!
//! A 4 × 5 panel (4 chains of 5 bones, 0.1 m apart) hangs from a root that sways 0.2 m at
//! 1 Hz (`sin`), jumps 0.2 m (`step`) or turns (`turn`, the character itself turning), at
//! 30, 60 and 144 Hz, free, against a sphere and a capsule that swing through it, with the
//! surface collision on and off, with and without a virtual tip, hardness, drag, lift, wind,
//! the angle lock, the length limit, two iterations and two collision sub-iterations;
//! friction 0.3. Every point within 1e-5 m of the port, every frame (1e-4 m asked; 1.2e-7 m
//! measured, the f32 output's rounding); each bone where its point is; each bone turned
//! toward its child as SPCR turns it.
//!
//! The mode works in f64, as SPCR does on Unreal 5 (whose `FVector` is double). The port is
//! given the pose, the bodies and the parameters as the engine holds them (f32), so that
//! both meet the same numbers: SPCR's rules are not continuous (a point pushed onto a
//! collider touches it or not by the last bit, then takes all of the friction or none; a
//! hit crossing a triangle's edge; a capsule's end sphere taking over from its side), and
//! two codes fed different roundings part at the first such contact.

use glam::{DQuat, DVec3, Quat, Vec3};
use tassel::dynamics::cloth::{
    ClothMode, ClothSettings, CollisionSwitches, ConstraintSwitches, SurfaceCollision,
};
use tassel::dynamics::{ColliderSettings, RigSettings};
use tassel::{CharacterSim, Skeleton, SkeletonBuilder, Transform};

/// SPCR's written-out π of the wind phase.
#[allow(clippy::approx_constant)]
const SPCR_PI: f64 = 3.141592;

const CHAINS: usize = 4;
const BONES: usize = 5;
const SEG: f64 = 0.1;
const TOP: f64 = 2.0;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Motion {
    Sin,
    Step,
    Turn,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Body {
    None,
    Sphere,
    Capsule,
}

#[derive(Clone, Copy, Debug)]
struct Case {
    motion: Motion,
    body: Body,
    surface: bool,
    rate: f64,
    /// Extra settings: a virtual tip, hardness, an angle limit, wind, the length limit,
    /// two iterations, drag and lift.
    extras: bool,
}

/// SPCR's parameters for the case, Tassel's names and units.
struct Params {
    resistance: f64,
    hardness: f64,
    gravity: DVec3,
    tip: f64,
    iterations: u32,
    limit: f64,
    force_length: bool,
    wind: DVec3,
    wind_speed: f64,
    drag: f64,
    lift: f64,
    friction: f64,
    lod: u32,
    sub: u32,
}

/// The case's parameters, each rounded to f32 as an engine's properties hold them (the
/// rig gets the same values).
fn params(c: &Case) -> Params {
    let p = exact_params(c);
    let r = |x: f64| x as f32 as f64;
    let v = |x: DVec3| x.as_vec3().as_dvec3();
    Params {
        resistance: r(p.resistance),
        hardness: r(p.hardness),
        gravity: v(p.gravity),
        tip: r(p.tip),
        limit: r(p.limit),
        wind: v(p.wind),
        wind_speed: r(p.wind_speed),
        drag: r(p.drag),
        lift: r(p.lift),
        friction: r(p.friction),
        ..p
    }
}

fn exact_params(c: &Case) -> Params {
    Params {
        resistance: 0.05,
        hardness: if c.extras { 0.02 } else { 0.0 },
        gravity: DVec3::new(0.0, -9.81, 0.0),
        tip: if c.extras { 0.05 } else { 0.0 },
        iterations: if c.extras { 2 } else { 1 },
        limit: if c.extras { 40.0 } else { 0.0 },
        force_length: c.extras,
        wind: if c.extras {
            DVec3::new(0.0, 0.0, 3.0)
        } else {
            DVec3::ZERO
        },
        wind_speed: 2.0,
        drag: if c.extras { 0.5 } else { 0.0 },
        lift: if c.extras { 0.3 } else { 0.0 },
        friction: 0.3,
        lod: 2,
        sub: if c.extras { 2 } else { 1 },
    }
}

// ---------------------------------------------------------------- the scene

/// The root's transform (character space) at time `t`.
fn root_at(m: Motion, t: f64) -> (DVec3, DQuat) {
    match m {
        Motion::Sin => (
            DVec3::new(0.2 * (std::f64::consts::TAU * t).sin(), 0.0, 0.0),
            DQuat::IDENTITY,
        ),
        Motion::Step => (
            DVec3::new(if t >= 0.5 { 0.2 } else { 0.0 }, 0.0, 0.0),
            DQuat::IDENTITY,
        ),
        Motion::Turn => (DVec3::ZERO, DQuat::IDENTITY),
    }
}

/// The character's own transform (world) at time `t`: it turns in `turn`.
fn component_at(m: Motion, t: f64) -> (DVec3, DQuat) {
    match m {
        Motion::Turn => (
            DVec3::new(0.1 * t, 0.0, 0.0),
            DQuat::from_rotation_y(0.8 * (std::f64::consts::TAU * 0.5 * t).sin()),
        ),
        _ => (DVec3::ZERO, DQuat::IDENTITY),
    }
}

/// The collider bone (character space): swings through the panel along Z.
fn body_at(t: f64) -> (DVec3, DQuat) {
    let z = 0.3 * (std::f64::consts::TAU * 0.7 * t).cos();
    (
        DVec3::new(0.15, TOP - 0.25, z),
        DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2),
    )
}

const SPHERE_R: f64 = 0.08;
const CAPSULE_R: f64 = 0.05;
const CAPSULE_LEN: f64 = 0.2;

fn skeleton() -> Skeleton {
    let mut b = SkeletonBuilder::new();
    let scene = b.add("scene", None, Transform::IDENTITY);
    let root = b.add("root", Some(scene), Transform::IDENTITY);
    b.add("body", Some(scene), Transform::IDENTITY);
    for c in 0..CHAINS {
        let mut p = b.add(
            format!("c{c}_0"),
            Some(root),
            Transform::from_translation(Vec3::new((c as f64 * SEG) as f32, TOP as f32, 0.0)),
        );
        for i in 1..BONES {
            p = b.add(
                format!("c{c}_{i}"),
                Some(p),
                Transform::from_translation(Vec3::new(0.0, -SEG as f32, 0.0)),
            );
        }
    }
    b.build().unwrap().0
}

fn rig(c: &Case) -> RigSettings {
    let p = params(c);
    let mut rig = RigSettings::default();
    match c.body {
        Body::None => {}
        Body::Sphere => rig.colliders.push(ColliderSettings {
            name: "body".into(),
            bone: "body".into(),
            shape: tassel::collide::Shape::Sphere {
                radius: SPHERE_R as f32,
                inside: false,
            },
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            mirror: None,
            mirror_bone: String::new(),
        }),
        Body::Capsule => rig.colliders.push(ColliderSettings {
            name: "body".into(),
            bone: "body".into(),
            shape: tassel::collide::Shape::Capsule {
                radius: CAPSULE_R as f32,
                length: CAPSULE_LEN as f32,
            },
            offset: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            mirror: None,
            mirror_bone: String::new(),
        }),
    }
    let mut s = ClothSettings::spcr();
    s.name = "panel".into();
    s.mode = ClothMode::Spcr;
    s.chains = (0..CHAINS)
        .map(|k| [format!("c{k}_0"), format!("c{k}_{}", BONES - 1)])
        .collect();
    s.constraints = ConstraintSwitches {
        structural_vertical: true,
        structural_horizontal: true,
        shear: true,
        bending_vertical: true,
        bending_horizontal: true,
    };
    s.collision = Some(CollisionSwitches {
        structural_vertical: true,
        structural_horizontal: true,
        shear: false,
    });
    s.resistance = p.resistance as f32;
    s.hardness = p.hardness as f32;
    s.gravity = p.gravity.as_vec3();
    s.virtual_bone_length = p.tip as f32;
    s.iterations = p.iterations;
    s.limit_angle = p.limit as f32;
    s.force_length_limit = p.force_length;
    s.wind.acceleration = p.wind.as_vec3();
    s.wind.speed = Some(p.wind_speed as f32);
    s.drag = p.drag as f32;
    s.lift = p.lift as f32;
    s.friction = p.friction as f32;
    s.collision_lod = Some(p.lod);
    s.collision_sub_iterations = Some(p.sub);
    s.surface_collision = if c.surface {
        SurfaceCollision::PushPull
    } else {
        SurfaceCollision::Off
    };
    s.teleport_distance = 0.0;
    s.teleport_angle = 0.0;
    rig.cloths.push(s);
    rig
}

/// The animated locals (the root and the body moved) and the character's transform at
/// time `t`, in f32 as an engine holds them.
fn animated(sk: &Skeleton, m: Motion, t: f64) -> (Vec<Transform>, Transform) {
    let mut locals = sk.rest().to_vec();
    let (rt, rr) = root_at(m, t);
    locals[sk.find("root").unwrap()] =
        Transform::from_translation_rotation(rt.as_vec3(), rr.as_quat());
    let (bt, br) = body_at(t);
    locals[sk.find("body").unwrap()] =
        Transform::from_translation_rotation(bt.as_vec3(), br.as_quat());
    let (ct, cr) = component_at(m, t);
    (
        locals,
        Transform::from_translation_rotation(ct.as_vec3(), cr.as_quat()),
    )
}

/// The component-space transforms of `locals` (the engine's pose, which SPCR reads).
fn models_of(sk: &Skeleton, locals: &[Transform]) -> Vec<Transform> {
    let mut models = vec![Transform::IDENTITY; sk.len()];
    tassel::LocalToModelJob {
        skeleton: sk,
        root: Transform::IDENTITY,
        locals,
        models: &mut models,
    }
    .run()
    .unwrap();
    models
}

// ---------------------------------------------------------------- the port (f64)

/// Unreal's `FMath::Clamp` (NaN gives the upper bound).
fn clamp(x: f64, lo: f64, hi: f64) -> f64 {
    if x < lo {
        lo
    } else if x < hi {
        x
    } else {
        hi
    }
}

/// `GetSafeNormal` (tolerance 1e-8 cm² = 1e-12 m²).
fn safe(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq == 1.0 {
        v
    } else if sq < 1e-12 {
        DVec3::ZERO
    } else {
        v / sq.sqrt()
    }
}

/// `FVector::Normalize`.
fn norm(v: DVec3) -> DVec3 {
    let sq = v.length_squared();
    if sq > 1e-12 {
        v / sq.sqrt()
    } else {
        v
    }
}

fn lerp(a: DVec3, b: DVec3, t: f64) -> DVec3 {
    a + (b - a) * t
}

#[derive(Clone, Copy, Default)]
struct Point {
    /// (chain, index) of the bone, `None` for a virtual point.
    real: bool,
    pos: DVec3,
    prev: DVec3,
    initial: DVec3,
    cs_bone_dir: DVec3,
    weight: f64,
    resistance: f64,
    gravity: f64,
    friction: f64,
    hardness: f64,
    drag: f64,
    lift: f64,
}

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    StructuralVertical,
    StructuralHorizontal,
    Shear,
    BendingVertical,
    BendingHorizontal,
}

#[derive(Clone, Copy)]
struct Constraint {
    a: (usize, usize),
    b: (usize, usize),
    length: f64,
    collide: bool,
    _kind: Kind,
}

#[derive(Clone, Copy, Default)]
struct Collider {
    capsule: bool,
    radius: f64,
    height: f64,
    friction: f64,
    position: DVec3,
    direction: DVec3,
    position_prev: DVec3,
    direction_prev: DVec3,
    position_prev_frame: DVec3,
    direction_prev_frame: DVec3,
}

/// One frame's animated pose, as SPCR reads it: component transform, and each bone's
/// component-space transform.
struct Frame {
    comp: (DVec3, DQuat),
    /// [chain][bone]: (position, rotation) in component space.
    bones: Vec<Vec<(DVec3, DQuat)>>,
    /// The body collider's bone, world (f32, as the engine gives it).
    body: Transform,
}

impl Frame {
    /// The pose as the engine hands it to SPCR: the bones' component-space transforms
    /// (`models`, f32) and the component's (f32); the body's world transform is the f32
    /// product the engine forms (`BoneCSTransform * ComponentTransform`).
    fn of(sk: &Skeleton, models: &[Transform], comp: Transform) -> Frame {
        let bones = (0..CHAINS)
            .map(|c| {
                (0..BONES)
                    .map(|i| {
                        let m = models[sk.find(&format!("c{c}_{i}")).unwrap()];
                        (m.translation.as_dvec3(), m.rotation.as_dquat())
                    })
                    .collect()
            })
            .collect();
        let b = models[sk.find("body").unwrap()];
        let body = comp * Transform::from_translation_rotation(b.translation, b.rotation);
        Frame {
            comp: (comp.translation.as_dvec3(), comp.rotation.as_dquat()),
            bones,
            body,
        }
    }

    fn to_world(&self, p: DVec3) -> DVec3 {
        self.comp.0 + self.comp.1 * p
    }

    fn bone_world(&self, c: usize, i: usize) -> DVec3 {
        self.to_world(self.bones[c][i].0)
    }
}

/// One of Tassel's `fixed` choices put into the port in SPCR's place (the table of
/// `docs/cloth.md`): each switched on alone measures what that difference moves.
#[derive(Clone, Copy, Default, Debug)]
struct Variant {
    /// The fixed points at each step's time (linearly between the frames), not on the
    /// frame's end pose at every step.
    step_targets: bool,
    /// The output blended between the last two steps (one step behind, as `fixed`), not
    /// the last step.
    blend_output: bool,
    /// The bones only turned toward their child (their places from their parents), not
    /// moved to the points.
    turn_only: bool,
    /// The constraints per chain, then per pair of chains, without the bottom row's
    /// clamped pairs.
    tassel_order: bool,
    /// `d = (v(1 − r) + g·h²)(1 − f)`, not `d = (g·h²/2 + v)(1 − r)(1 − f)`.
    tassel_gravity: bool,
}

struct Port {
    variant: Variant,
    /// The fixed points' world places at the last frame's end (for `step_targets`).
    last_frame: Vec<DVec3>,
    /// Every point after the step before the last (for `blend_output`).
    before: Vec<Vec<DVec3>>,
    p: Params,
    case: Case,
    pts: Vec<Vec<Point>>,
    cons: Vec<Constraint>,
    /// `[A, B, C, D]` of each surface constraint.
    surfaces: Vec<[(usize, usize); 4]>,
    colliders: Vec<Collider>,
    rest: f32,
    wind_radians: f64,
    /// [chain][bone]: the written bone (position, rotation), component space.
    out: Vec<Vec<(DVec3, DQuat)>>,
}

impl Port {
    /// `OnResetAll` on frame `f`.
    fn new(case: Case, f: &Frame) -> Port {
        Port::with(case, f, Variant::default())
    }

    /// The port with one of Tassel's choices in SPCR's place.
    fn with(case: Case, f: &Frame, variant: Variant) -> Port {
        let p = params(&case);
        let need_virtual = p.tip > 0.0;
        let mut pts = Vec::new();
        for c in 0..CHAINS {
            let mut chain = Vec::new();
            let n = BONES;
            for i in 0..n {
                chain.push(Point {
                    real: true,
                    weight: if i == 0 { 0.0 } else { 1.0 },
                    ..Point::default()
                });
            }
            if need_virtual {
                chain.push(Point {
                    real: false,
                    weight: 1.0,
                    ..Point::default()
                });
            }
            for pt in chain.iter_mut() {
                pt.resistance = 1.0 - clamp(p.resistance, 0.0, 1.0);
                pt.gravity = 1.0;
                pt.hardness = clamp(p.hardness, 0.0, 1.0);
                // Tassel's drag (per metre, speed lost drag·|v|²·h) is SPCR's coefficient
                // halved; its lift (spcr mode: m/s²) a push of lift·h² per step.
                pt.drag = clamp(2.0 * p.drag, 0.0, 100.0);
                let h = 1.0f32 / 120.0;
                pt.lift = p.lift * clamp(1.0, 0.0, 1.0) * (h as f64) * (h as f64);
            }
            for i in 0..chain.len() {
                if chain[i].real {
                    chain[i].pos = f.bone_world(c, i);
                } else {
                    let (p0, p1) = (chain[i - 2].pos, chain[i - 1].pos);
                    let dir = safe(p1 - p0);
                    chain[i].pos = p1 + dir * p.tip;
                    let rot = f.bones[c][i - 1].1;
                    chain[i - 1].cs_bone_dir = rot.inverse() * (p1 - chain[i].pos);
                }
                chain[i].prev = chain[i].pos;
                chain[i].initial = chain[i].pos;
            }
            pts.push(chain);
        }
        let last_frame = (0..CHAINS).map(|c| f.bone_world(c, 0)).collect();
        let before = pts
            .iter()
            .map(|ch: &Vec<Point>| ch.iter().map(|q| q.pos).collect())
            .collect();
        let mut port = Port {
            variant,
            last_frame,
            before,
            p,
            case,
            pts,
            cons: Vec::new(),
            surfaces: Vec::new(),
            colliders: Vec::new(),
            rest: 0.0,
            wind_radians: 0.0,
            out: vec![vec![(DVec3::ZERO, DQuat::IDENTITY); BONES]; CHAINS],
        };
        port.create_constraints();
        port.create_surfaces();
        if case.body != Body::None {
            port.colliders.push(Collider {
                capsule: case.body == Body::Capsule,
                friction: port.p.friction,
                ..Collider::default()
            });
            // `InitializeColliderPositionOld`.
            let (pos, dir, radius, height) = port.body_place(f);
            let c = &mut port.colliders[0];
            c.radius = radius;
            c.height = height;
            c.position_prev_frame = pos;
            c.direction_prev_frame = dir;
            // (Unreal leaves `Position` unset until the first step; it is overwritten
            // before any use with one sub-iteration.)
            c.position = pos;
            c.direction = dir;
        }
        port
    }

    /// The body collider's SPCR place on frame `f`: bottom end, full axis, radius, height.
    /// Its ends come from the engine's f32 transform, as Unreal hands SPCR its bodies.
    fn body_place(&self, f: &Frame) -> (DVec3, DVec3, f64, f64) {
        let centre = f.body.translation;
        match self.case.body {
            Body::Capsule => {
                let len = CAPSULE_LEN as f32;
                // Tassel's capsules run along their bone's +Y (Unreal's along Z).
                let axis = f.body.rotation * Vec3::Y * (0.5 * len);
                let (bottom, top) = ((centre - axis).as_dvec3(), (centre + axis).as_dvec3());
                (bottom, top - bottom, CAPSULE_R as f32 as f64, len as f64)
            }
            _ => (centre.as_dvec3(), DVec3::ZERO, SPHERE_R as f32 as f64, 0.0),
        }
    }

    fn add(&mut self, kind: Kind, a: (usize, usize), b: (usize, usize), collide: bool) {
        let (pa, pb) = (self.pts[a.0][a.1], self.pts[b.0][b.1]);
        if pa.weight > 0.0 || pb.weight > 0.0 {
            self.cons.push(Constraint {
                a,
                b,
                length: (pa.pos - pb.pos).length(),
                collide,
                _kind: kind,
            });
        }
    }

    /// `CreateConstraints`: bending horizontal, bending vertical, shear, structural
    /// horizontal, structural vertical. The panel is not a loop.
    fn create_constraints(&mut self) {
        if self.variant.tassel_order {
            return self.create_constraints_tassel_order();
        }
        let n = self.pts.len();
        let len = |port: &Port, t: usize| port.pts[t].len();
        // Bending horizontal (no collision).
        for t in 0..n.saturating_sub(2) {
            let (na, nb) = (len(self, t), len(self, t + 2));
            for i in 0..na.max(nb) {
                self.add(
                    Kind::BendingHorizontal,
                    (t, i.min(na - 1)),
                    (t + 2, i.min(nb - 1)),
                    false,
                );
            }
        }
        // Bending vertical (no collision).
        for t in 0..n {
            for i in 0..len(self, t).saturating_sub(2) {
                self.add(Kind::BendingVertical, (t, i), (t, i + 2), false);
            }
        }
        // Shear (bShear_Collision off).
        for t in 0..n - 1 {
            let (na, nb) = (len(self, t), len(self, t + 1));
            for i in 0..na.max(nb) {
                self.add(
                    Kind::Shear,
                    (t, (i + 1).min(na - 1)),
                    (t + 1, i.min(nb - 1)),
                    false,
                );
            }
            for i in 0..na.max(nb) {
                self.add(
                    Kind::Shear,
                    (t, i.min(na - 1)),
                    (t + 1, (i + 1).min(nb - 1)),
                    false,
                );
            }
        }
        // Structural horizontal (collision on in this test).
        for t in 0..n - 1 {
            let (na, nb) = (len(self, t), len(self, t + 1));
            for i in 0..na.max(nb) {
                self.add(
                    Kind::StructuralHorizontal,
                    (t, i.min(na - 1)),
                    (t + 1, i.min(nb - 1)),
                    true,
                );
            }
        }
        // Structural vertical (collision on), step count 1.
        for t in 0..n {
            for i in 0..len(self, t) - 1 {
                self.add(Kind::StructuralVertical, (t, i), (t, i + 1), true);
            }
        }
    }

    /// (Variant) Tassel's order: per chain (structural, then bending along it), then per
    /// pair of chains (structural across, both shear diagonals of each quad), then bending
    /// across; no clamped pairs past the shorter chain.
    fn create_constraints_tassel_order(&mut self) {
        let n = self.pts.len();
        for t in 0..n {
            let len = self.pts[t].len();
            for i in 0..len {
                if i + 1 < len {
                    self.add(Kind::StructuralVertical, (t, i), (t, i + 1), true);
                }
                if i + 2 < len {
                    self.add(Kind::BendingVertical, (t, i), (t, i + 2), false);
                }
            }
        }
        for t in 0..n - 1 {
            let m = self.pts[t].len().min(self.pts[t + 1].len());
            for i in 0..m {
                self.add(Kind::StructuralHorizontal, (t, i), (t + 1, i), true);
                if i + 1 < m {
                    self.add(Kind::Shear, (t, i), (t + 1, i + 1), false);
                    self.add(Kind::Shear, (t + 1, i), (t, i + 1), false);
                }
            }
        }
        for t in 0..n.saturating_sub(2) {
            let m = self.pts[t].len().min(self.pts[t + 2].len());
            for i in 0..m {
                self.add(Kind::BendingHorizontal, (t, i), (t + 2, i), false);
            }
        }
    }

    /// `CreateSurfaceConstraints`.
    fn create_surfaces(&mut self) {
        let n = self.pts.len();
        for t in 0..n - 1 {
            let (na, nb) = (self.pts[t].len(), self.pts[t + 1].len());
            for i in 0..na.max(nb) {
                let a = (t, i.min(na - 1));
                let b = (t + 1, i.min(nb - 1));
                let ac = (t, (i + 1).min(na - 1));
                let bc = (t + 1, (i + 1).min(nb - 1));
                let w = |x: (usize, usize)| self.pts[x.0][x.1].weight;
                if w(a) > 0.0 || w(b) > 0.0 || w(ac) > 0.0 || w(bc) > 0.0 {
                    self.surfaces.push([a, b, bc, ac]);
                }
            }
        }
    }

    /// `EvaluateSkeletalControl_AnyThread` for a frame of `dt` seconds ending on `f`.
    fn evaluate(&mut self, f: &Frame, dt: f32) {
        let start = self.rest;
        self.rest += dt;
        let one_step: f32 = 1.0 / 120.0;
        let loops = (self.rest / one_step) as i32;
        for i in (0..loops).rev() {
            self.rest -= one_step;
            // (Variant) where this step's end lies in the frame.
            let k = (loops - i) as f64;
            let w = ((k * one_step as f64 - start as f64) / dt as f64).clamp(0.0, 1.0);
            self.before = self
                .pts
                .iter()
                .map(|ch| ch.iter().map(|q| q.pos).collect())
                .collect();
            let mut wind = DVec3::ZERO;
            if self.p.wind_speed > 0.0 {
                self.wind_radians += one_step as f64 * self.p.wind_speed;
                while self.wind_radians > SPCR_PI {
                    self.wind_radians -= SPCR_PI * 2.0;
                }
                while self.wind_radians < -SPCR_PI {
                    self.wind_radians += SPCR_PI * 2.0;
                }
                wind = self.p.wind * (self.wind_radians.sin() * 0.5 + 0.5);
            }
            self.update_control_points(f, wind, one_step, w);
            for relax in 1..=self.p.iterations {
                let delta = relax as f64 / self.p.iterations as f64;
                self.update_colliders(f, delta);
                self.update_constraints();
                if i % self.p.lod as i32 == 0 {
                    for sub in 1..=self.p.sub {
                        let sub_delta = sub as f64 / self.p.sub as f64;
                        self.update_collision(sub_delta);
                        if self.case.surface {
                            self.update_surface_collision(sub_delta);
                        }
                    }
                }
            }
            if self.p.limit > 0.0 {
                self.update_lock_angles();
            }
        }
        if self.p.force_length {
            self.force_fix_constraints();
        }
        self.apply_to_bone(f);
        self.last_frame = (0..CHAINS).map(|c| f.bone_world(c, 0)).collect();
        for c in &mut self.colliders {
            c.position_prev_frame = c.position;
            c.direction_prev_frame = c.direction;
        }
    }

    fn update_control_points(&mut self, f: &Frame, wind: DVec3, h: f32, w: f64) {
        // `const float StepTime_x2_Half = DeltaTime * DeltaTime * 0.5f;`
        let half = (h * h * 0.5) as f64;
        let g = self.p.gravity;
        for c in 0..self.pts.len() {
            // `while (iPoint <= FixedPointIndex)`, with FixedPointIndex 0.
            let fixed_point_index = 0;
            let mut i = 0;
            while i <= fixed_point_index {
                let mut here = f.bone_world(c, i);
                if self.variant.step_targets {
                    here = lerp(self.last_frame[c], here, w);
                }
                self.pts[c][i].pos = here;
                self.pts[c][i].prev = here;
                i += 1;
            }
            while i < self.pts[c].len() {
                let pt = self.pts[c][i];
                let mut d = g * pt.gravity;
                d += wind;
                d *= half;
                d += pt.pos - pt.prev;
                d *= pt.resistance;
                d *= 1.0 - clamp(pt.friction, 0.0, 1.0);
                if self.variant.tassel_gravity {
                    let h2 = (h as f64) * (h as f64);
                    d = ((pt.pos - pt.prev) * pt.resistance + (g * pt.gravity + wind) * h2)
                        * (1.0 - clamp(pt.friction, 0.0, 1.0));
                }
                if self.p.drag > 0.0 {
                    let speed = d.length_squared();
                    let n = safe(d);
                    d += -1.0 * ((pt.drag * speed * n) / 2.0);
                }
                if self.p.lift > 0.0 {
                    let motion = safe(d);
                    let side = motion.cross(safe(g));
                    let lift = motion.cross(side);
                    d += lift * pt.lift;
                }
                let q = &mut self.pts[c][i];
                q.prev = q.pos;
                q.pos += d;
                q.friction = 0.0;
                if q.hardness > 0.0 {
                    let target = if !q.real {
                        // The parent's transform applied to its `CSBoneDirection`.
                        let parent = self.pts[c][i - 1];
                        let (bp, br) = f.bones[c][i - 1];
                        let world_rot = f.comp.1 * br;
                        f.to_world(bp) + world_rot * parent.cs_bone_dir
                    } else {
                        f.bone_world(c, i)
                    };
                    let q = &mut self.pts[c][i];
                    q.pos += (target - q.pos) * q.hardness;
                }
                i += 1;
            }
        }
    }

    fn update_colliders(&mut self, f: &Frame, delta: f64) {
        if self.colliders.is_empty() {
            return;
        }
        let (pos, dir, radius, height) = self.body_place(f);
        let c = &mut self.colliders[0];
        c.radius = radius;
        c.height = height;
        c.position_prev = c.position;
        c.position = lerp(c.position_prev_frame, pos, delta);
        if c.capsule {
            c.direction_prev = c.direction;
            c.direction = lerp(c.direction_prev_frame, dir, delta);
        }
    }

    fn update_constraints(&mut self) {
        for k in 0..self.cons.len() {
            let con = self.cons[k];
            let (a, b) = (self.pts[con.a.0][con.a.1], self.pts[con.b.0][con.b.1]);
            if a.weight + b.weight < 0.001 {
                continue;
            }
            // Every strength curve is 1 here, both ways.
            let power = 1.0;
            let dir = b.pos - a.pos;
            let force = dir.length() - con.length;
            let disp = safe(dir) * (force * power);
            let w = a.weight + b.weight;
            self.pts[con.a.0][con.a.1].pos += disp * a.weight / w;
            self.pts[con.b.0][con.b.1].pos -= disp * b.weight / w;
        }
    }

    fn update_collision(&mut self, delta: f64) {
        for k in 0..self.cons.len() {
            let con = self.cons[k];
            if !con.collide {
                continue;
            }
            let (wa, wb) = (
                self.pts[con.a.0][con.a.1].weight,
                self.pts[con.b.0][con.b.1].weight,
            );
            if wa + wb < 0.001 {
                continue;
            }
            for col in self.colliders.clone() {
                if wa > 0.0 {
                    let p = &mut self.pts[con.a.0][con.a.1].pos;
                    *p = pushout_from_collider(&col, *p, delta);
                }
                if wb > 0.0 {
                    let p = &mut self.pts[con.b.0][con.b.1].pos;
                    *p = pushout_from_collider(&col, *p, delta);
                }
            }
            let mut friction: f64 = 0.0;
            for col in self.colliders.clone() {
                let (pa, pb) = (
                    self.pts[con.a.0][con.a.1].pos,
                    self.pts[con.b.0][con.b.1].pos,
                );
                if let Some((on_line, on_col, radius)) = collision_detection(&col, pa, pb, delta) {
                    let mut push = on_line - on_col;
                    let dist = push.length();
                    let half = (pb - pa).length() * 0.5;
                    let rate1 = clamp((on_line - pa).length() / half, 0.0, 1.0);
                    let rate2 = clamp((on_line - pb).length() / half, 0.0, 1.0);
                    if dist > 0.0 {
                        push /= dist;
                        push *= (radius - dist).max(0.0);
                        if wa > 0.0 {
                            self.pts[con.a.0][con.a.1].pos += push * rate2;
                        }
                        if wb > 0.0 {
                            self.pts[con.b.0][con.b.1].pos += push * rate1;
                        }
                    }
                    let dot = DVec3::Y.dot(safe(on_line - on_col));
                    friction = friction.max(col.friction * clamp(dot.abs(), 0.0, 1.0));
                }
            }
            let a = &mut self.pts[con.a.0][con.a.1];
            a.friction = friction.max(a.friction);
            let b = &mut self.pts[con.b.0][con.b.1];
            b.friction = friction.max(b.friction);
        }
    }

    fn update_surface_collision(&mut self, delta: f64) {
        for s in self.surfaces.clone() {
            let tris = [s[0], s[1], s[2], s[2], s[3], s[0]];
            for col in self.colliders.clone() {
                for t in 0..2 {
                    let ids = [tris[3 * t], tris[3 * t + 1], tris[3 * t + 2]];
                    let at = |port: &Port, x: (usize, usize)| port.pts[x.0][x.1].pos;
                    let (a, b, c) = (at(self, ids[0]), at(self, ids[1]), at(self, ids[2]));
                    if let Some((hit, push, radius)) = check_collision(a, b, c, &col, delta) {
                        let centre = centre_of_triangle(a, b, c);
                        let magnitude = push.length();
                        let push = norm(push);
                        for &v in &ids {
                            let p = at(self, v);
                            let rate = (p - centre).length() / (p - hit).length();
                            let rate = clamp(rate.abs(), 0.0, 1.0);
                            self.pts[v.0][v.1].pos += push * (radius - magnitude) * rate;
                        }
                    }
                }
            }
        }
    }

    fn update_lock_angles(&mut self) {
        for c in 0..self.pts.len() {
            for i in 0..self.pts[c].len() {
                if !self.pts[c][i].real || i == 0 {
                    continue;
                }
                let parent = self.pts[c][i - 1];
                let super_parent = if i >= 2 {
                    self.pts[c][i - 2].pos
                } else {
                    parent.pos
                };
                let me = self.pts[c][i];
                let bone = me.pos - parent.pos;
                let mut parent_dir = parent.pos - super_parent;
                if parent_dir.length() == 0.0 {
                    parent_dir = me.initial - parent.initial;
                }
                let angle = safe(parent_dir).dot(safe(bone)).acos().to_degrees();
                let remaining = angle - self.p.limit;
                if remaining > 0.0 {
                    let axis = safe(parent_dir.cross(bone));
                    self.pts[c][i].pos = parent.pos + rotate_angle_axis(bone, -remaining, axis);
                }
            }
        }
    }

    fn force_fix_constraints(&mut self) {
        for con in self.cons.clone() {
            let a = self.pts[con.a.0][con.a.1].pos;
            let b = self.pts[con.b.0][con.b.1].pos;
            let dir = b - a;
            if dir.length() > con.length {
                self.pts[con.b.0][con.b.1].pos = a + safe(dir) * con.length;
            }
        }
    }

    fn apply_to_bone(&mut self, f: &Frame) {
        let inv = f.comp.1.inverse();
        let cs = |p: DVec3| inv * (p - f.comp.0);
        let share = (self.rest / (1.0f32 / 120.0)) as f64;
        for c in 0..self.pts.len() {
            // What is shown: the last step (SPCR), or (variant) the blend of the last two.
            let shown: Vec<DVec3> = (0..self.pts[c].len())
                .map(|i| {
                    let p = self.pts[c][i].pos;
                    if self.variant.blend_output {
                        cs(lerp(self.before[c][i], p, share))
                    } else {
                        cs(p)
                    }
                })
                .collect();
            let mut turned_parent: Option<(DVec3, DQuat)> = None;
            for i in 0..BONES {
                let (bp, br) = f.bones[c][i];
                let mut rot = br;
                let mut add = DQuat::IDENTITY;
                if i + 1 < self.pts[c].len() {
                    let child = self.pts[c][i + 1];
                    let to_target = shown[i] - shown[i + 1];
                    let to_current = if !child.real {
                        br * self.pts[c][i].cs_bone_dir
                    } else {
                        bp - f.bones[c][i + 1].0
                    };
                    add = find_between_normals(safe(to_current), safe(to_target));
                    rot = add * br;
                }
                let at = match turned_parent {
                    // (Variant) the bone where its turned parent takes it.
                    Some((parent_at, parent_add)) if self.variant.turn_only => {
                        parent_at + parent_add * (bp - f.bones[c][i - 1].0)
                    }
                    _ => shown[i],
                };
                turned_parent = Some((at, add));
                self.out[c][i] = (at, rot);
            }
        }
    }
}

/// Unreal's `FVector::RotateAngleAxis(AngleDeg, Axis)` (its rotation matrix, written out).
fn rotate_angle_axis(v: DVec3, angle_deg: f64, axis: DVec3) -> DVec3 {
    let (s, c) = angle_deg.to_radians().sin_cos();
    let (xx, yy, zz) = (axis.x * axis.x, axis.y * axis.y, axis.z * axis.z);
    let (xy, yz, zx) = (axis.x * axis.y, axis.y * axis.z, axis.z * axis.x);
    let (xs, ys, zs) = (axis.x * s, axis.y * s, axis.z * s);
    let omc = 1.0 - c;
    DVec3::new(
        (omc * xx + c) * v.x + (omc * xy - zs) * v.y + (omc * zx + ys) * v.z,
        (omc * xy + zs) * v.x + (omc * yy + c) * v.y + (omc * yz - xs) * v.z,
        (omc * zx - ys) * v.x + (omc * yz + xs) * v.y + (omc * zz + c) * v.z,
    )
}

/// `FQuat::FindBetweenNormals`.
fn find_between_normals(a: DVec3, b: DVec3) -> DQuat {
    let w = 1.0 + a.dot(b);
    let (x, y, z, w) = if w >= 1e-6 {
        let c = a.cross(b);
        (c.x, c.y, c.z, w)
    } else if a.x.abs() > a.y.abs() {
        (-a.z, 0.0, a.x, 0.0)
    } else {
        (0.0, -a.z, a.y, 0.0)
    };
    DQuat::from_xyzw(x, y, z, w).normalize()
}

fn pushout_from_sphere(centre: DVec3, radius: f64, p: DVec3) -> DVec3 {
    let d = p - centre;
    let sq = d.length_squared();
    if sq > 1e-8 && sq < radius * radius {
        return centre + d * radius / sq.sqrt();
    }
    p
}

fn pushout_from_collider(c: &Collider, p: DVec3, delta: f64) -> DVec3 {
    if c.capsule {
        let vec = lerp(c.direction_prev, c.direction, delta);
        let n = norm(vec);
        let pos = lerp(c.position_prev, c.position, delta);
        let along = n.dot(p - pos);
        if along <= 0.0 {
            pushout_from_sphere(pos, c.radius, p)
        } else if along >= c.height {
            pushout_from_sphere(pos + vec, c.radius, p)
        } else {
            let on = pos + n * along;
            let out = p - on;
            let sq = out.length_squared();
            if sq > 1e-7 && sq < c.radius * c.radius {
                on + out * c.radius / sq.sqrt()
            } else {
                p
            }
        }
    } else {
        pushout_from_sphere(lerp(c.position_prev, c.position, delta), c.radius, p)
    }
}

fn detection_sphere(centre: DVec3, radius: f64, p1: DVec3, p2: DVec3) -> Option<(DVec3, DVec3)> {
    let mut dir = p2 - p1;
    let len = dir.length();
    dir /= len;
    let dot = dir.dot(centre - p1);
    let on_line = dir * clamp(dot, 0.0, len) + p1;
    ((centre - on_line).length_squared() <= radius * radius).then_some((on_line, centre))
}

/// `CollisionDetection` (a segment of no length meets nothing: SPCR divides by it).
fn collision_detection(
    c: &Collider,
    p1: DVec3,
    p2: DVec3,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    if (p2 - p1).length_squared() == 0.0 {
        return None;
    }
    let pos = lerp(c.position_prev, c.position, delta);
    if !c.capsule {
        return detection_sphere(pos, c.radius, p1, p2).map(|(l, o)| (l, o, c.radius));
    }
    let dir = lerp(c.direction_prev, c.direction, delta);
    if let Some((l, o)) = detection_sphere(pos, c.radius, p1, p2) {
        return Some((l, o, c.radius));
    }
    if let Some((l, o)) = detection_sphere(pos + dir, c.radius, p1, p2) {
        return Some((l, o, c.radius));
    }
    let pd = p2 - p1;
    // `ComputeNearestPoints(capsulePos, capsuleDir, point1, pointDir)`.
    let n1 = dir.cross(pd.cross(dir));
    let n2 = pd.cross(dir.cross(pd));
    let t1 = (p1 - pos).dot(n2) / dir.dot(n2);
    let t2 = (pos - p1).dot(n1) / pd.dot(n1);
    let sq = ((p1 + pd * t2) - (pos + dir * t1)).length_squared();
    if sq > c.radius * c.radius {
        return None;
    }
    let t1 = clamp(t1, 0.0, 1.0);
    let t2 = clamp(t2, 0.0, 1.0);
    let on_col = pos + dir * t1;
    let on_line = p1 + pd * t2;
    ((on_col - on_line).length_squared() <= c.radius * c.radius)
        .then_some((on_line, on_col, c.radius))
}

fn centre_of_triangle(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    lerp(lerp(a, b, 0.5), lerp(a, c, 0.5), 0.5)
}

fn triangle_contains(a: DVec3, b: DVec3, c: DVec3, p: DVec3) -> bool {
    let (ap, bp, cp) = (a - p, b - p, c - p);
    let (u, v, w) = (ap.cross(bp), bp.cross(cp), cp.cross(ap));
    !(u.dot(v) < 0.0 || v.dot(w) < 0.0)
}

/// `SimpleRaycast`.
fn simple_raycast(origin: DVec3, dir: DVec3, n: DVec3, dist: f64) -> Option<f64> {
    let v = dir.dot(n);
    let o = -origin.dot(n) - dist;
    if v.abs() <= 0.001 {
        return None;
    }
    let enter = o / v;
    (enter > 1e-5).then_some(enter)
}

/// `CheckCollision` (the collider's `SurfaceColliderType` is PUSH: the mode's
/// `push_pull`).
fn check_collision(
    a: DVec3,
    b: DVec3,
    c: DVec3,
    col: &Collider,
    delta: f64,
) -> Option<(DVec3, DVec3, f64)> {
    let pos = lerp(col.position_prev, col.position, delta);
    let mut on_col = pos;
    let radius = col.radius;
    let dir = lerp(col.direction_prev, col.direction, delta);
    let dir_n = safe(dir);
    let centre = centre_of_triangle(a, b, c);
    let mut from_centre = norm(pos - centre);
    let mut normal = norm(safe(b - a).cross(safe(c - a)));
    let plane = -normal.dot(a);
    normal *= -1.0;
    let centre_dot = from_centre.dot(normal);
    if col.capsule {
        let side = dir_n.dot(normal) * centre_dot;
        from_centre = norm(normal * centre_dot * -1.0);
        let temp = on_col;
        if side < 0.0 {
            on_col = pos + (dir * 0.5) * 2.0;
        }
        let inverse = normal * -1.0;
        if let Some(enter) = simple_raycast(on_col, from_centre, inverse, plane) {
            let hit = on_col + from_centre * enter;
            if triangle_contains(a, b, c, hit) {
                let push = hit - on_col;
                return ((on_col - hit).length_squared() <= radius * radius)
                    .then_some((hit, push, radius));
            }
        } else {
            // SurfaceColliderType PUSH.
            on_col = temp;
            let end = pos + (dir * 0.5) * 2.0;
            if let Some(enter) = simple_raycast(on_col, dir, inverse, plane) {
                let hit = on_col + dir * enter;
                if triangle_contains(a, b, c, hit) {
                    let to_end = end - on_col;
                    let to_hit = hit - on_col;
                    let point_dot = (end - hit).dot(to_hit);
                    let line_dot = to_end.dot(to_end);
                    if !(point_dot >= 0.0 && point_dot <= line_dot) {
                        return None;
                    }
                    let ce = to_end.dot(to_hit);
                    let back = on_col + safe(to_end) * -radius;
                    let push = hit - back;
                    on_col += to_end * (ce / line_dot);
                    return ((on_col - hit).length_squared() <= radius * radius)
                        .then_some((hit, push, radius));
                }
            }
        }
    } else {
        let towards = normal * centre_dot * -1.0;
        if let Some(enter) = simple_raycast(pos, towards, normal * -1.0, plane) {
            let hit = pos + towards * enter;
            if triangle_contains(a, b, c, hit) {
                let push = hit - on_col;
                return ((on_col - hit).length_squared() <= radius * radius)
                    .then_some((hit, push, radius));
            }
        }
    }
    None
}

// ---------------------------------------------------------------- the comparison

/// Runs `case` for 2 s through Tassel's `spcr` mode and the port; returns the largest
/// point gap (m), the largest bone-to-point gap (m), the largest turn gap (rad), and the
/// largest distance any point moved from its start (the case is not still).
fn run(case: Case) -> (f64, f64, f64, f64) {
    let sk = skeleton();
    let mut sim = CharacterSim::new(sk.clone(), &rig(&case)).unwrap();
    let frames = (2.0 * case.rate).round() as usize;
    let dt = (1.0 / case.rate) as f32;
    let mut port: Option<Port> = None;
    let (mut worst, mut worst_bone, mut worst_turn, mut moved) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut start = Vec::new();
    for f in 0..frames {
        let t = f as f64 / case.rate;
        let step = if f == 0 { 0.0 } else { dt };
        let (locals, comp) = animated(&sk, case.motion, t);
        let frame = Frame::of(&sk, &models_of(&sk, &locals), comp);
        let pose = sim.frame(&locals, comp, step).unwrap().clone();
        let port = port.get_or_insert_with(|| Port::new(case, &frame));
        port.evaluate(&frame, step);
        let ours = sim.cloth_state().world_positions();
        let theirs: Vec<DVec3> = port.pts.iter().flatten().map(|p| p.pos).collect();
        assert_eq!(ours.len(), theirs.len());
        if start.is_empty() {
            start = theirs.clone();
        }
        for (k, (o, p)) in ours.iter().zip(&theirs).enumerate() {
            let gap = (o.as_dvec3() - *p).length();
            worst = worst.max(gap);
            moved = moved.max((*p - start[k]).length());
        }
        for c in 0..CHAINS {
            for i in 0..BONES {
                let j = sk.find(&format!("c{c}_{i}")).unwrap();
                let m = pose.models[j];
                let (want_p, want_r) = port.out[c][i];
                worst_bone = worst_bone.max((m.translation.as_dvec3() - want_p).length());
                let got = DQuat::from_xyzw(
                    m.rotation.x as f64,
                    m.rotation.y as f64,
                    m.rotation.z as f64,
                    m.rotation.w as f64,
                );
                // The angle of the turn between them (not `angle_between`, whose acos
                // of a dot near 1 reads f32 rounding as 7e-4 rad).
                let d = got.inverse() * want_r;
                let turn = 2.0 * d.xyz().length().atan2(d.w.abs());
                worst_turn = worst_turn.max(turn);
            }
        }
    }
    (worst, worst_bone, worst_turn, moved)
}

fn cases() -> Vec<Case> {
    let mut v = Vec::new();
    for rate in [30.0, 60.0, 144.0] {
        for motion in [Motion::Sin, Motion::Step, Motion::Turn] {
            for body in [Body::None, Body::Sphere, Body::Capsule] {
                for surface in [false, true] {
                    if body == Body::None && surface {
                        continue;
                    }
                    for extras in [false, true] {
                        v.push(Case {
                            motion,
                            body,
                            surface,
                            rate,
                            extras,
                        });
                    }
                }
            }
        }
    }
    v
}

#[test]
fn spcr_mode_follows_the_f64_port_of_spcr_within_1e4_m() {
    let mut failures = Vec::new();
    for case in cases() {
        let (gap, bone, turn, moved) = run(case);
        println!(
            "{:>5} Hz {:?} {:?} surface {} extras {}: point gap {gap:.2e} m, bone {bone:.2e} m, turn {turn:.2e} rad (moved {moved:.3} m)",
            case.rate, case.motion, case.body, case.surface, case.extras
        );
        assert!(moved > 0.02, "{case:?}: the cloth hardly moved ({moved} m)");
        // The issue asks for 1e-4 m; the two f64 codes agree to the f32 output's rounding
        // (1.2e-7 m measured), so a tenth of the way there is already a regression.
        let bound = 1e-5;
        if !(gap <= bound && bone <= bound && turn <= 1e-3) {
            failures.push(format!(
                "{case:?}: {gap:.2e} m / {bone:.2e} m / {turn:.2e} rad"
            ));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

const PANEL: &str = r#"
[[cloth]]
name = "panel"
chains = [["c0_0", "c0_4"], ["c1_0", "c1_4"]]
"#;

/// `mode = "spcr"` gives the keys a rig leaves out SPCR's defaults (its `MaxIterations`
/// 1, `bForceLengthLimit` off, `bUseSurfaceCollision` off, points without a radius, no
/// step cap), keeps the ones it gives, and the rig round-trips through the writer.
#[test]
fn an_spcr_cloth_takes_spcrs_defaults_for_the_keys_it_leaves_out() {
    let rig = RigSettings::from_toml_str(&format!("{PANEL}mode = \"spcr\"\n")).unwrap();
    let s = &rig.cloths[0];
    assert_eq!(s.mode, ClothMode::Spcr);
    assert_eq!(s.iterations, 1);
    assert!(!s.force_length_limit);
    assert_eq!(s.surface_collision, SurfaceCollision::Off);
    assert_eq!(s.radius, 0.0);
    assert_eq!(s.max_steps_per_frame, 64);
    let given = RigSettings::from_toml_str(&format!(
        "{PANEL}mode = \"spcr\"\niterations = 3\nradius = 0.01\nsurface_collision = \"push\"\n"
    ))
    .unwrap();
    let g = &given.cloths[0];
    assert_eq!((g.iterations, g.radius), (3, 0.01));
    assert_eq!(g.surface_collision, SurfaceCollision::Push);
    let again = RigSettings::from_toml_str(&given.to_toml_string().unwrap()).unwrap();
    assert_eq!(again.cloths[0], given.cloths[0]);
    // A fixed cloth keeps Tassel's defaults.
    let fixed = RigSettings::from_toml_str(PANEL).unwrap();
    assert_eq!(
        fixed.cloths[0],
        ClothSettings {
            name: "panel".into(),
            chains: fixed.cloths[0].chains.clone(),
            ..ClothSettings::default()
        }
    );
}

#[test]
fn the_spcr_keys_out_of_range_are_refused_by_name() {
    for (text, named) in [
        ("mode = \"spcr\"\ncollision_lod = 5\n", "collision_lod"),
        ("mode = \"spcr\"\ncollision_lod = 0\n", "collision_lod"),
        (
            "collision_sub_iterations = 11\n",
            "collision_sub_iterations",
        ),
        (
            "structural_vertical_step_count = 0\n",
            "structural_vertical_step_count",
        ),
        ("wind.speed = -1.0\n", "wind.speed"),
        ("mode = \"spcrr\"\n", "spcrr"),
        ("mode = \"spcr\"\ncollision = { shears = true }\n", "shears"),
    ] {
        let e = RigSettings::from_toml_str(&format!("{PANEL}{text}"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(named), "{text:?}: {e}");
    }
}

/// `SimMode::Spcr` (`--mode spcr`) switches every cloth to the mode and `fixed` back;
/// without a requested mode a rig whose first cloth says `spcr` and has no chains is
/// reported as `spcr`.
#[test]
fn the_spcr_sim_mode_switches_the_cloths() {
    use tassel::dynamics::SimMode;
    let mut rig = RigSettings::from_toml_str(PANEL).unwrap();
    let (mode, _) = SimMode::apply(Some(SimMode::Spcr), &mut rig, false).unwrap();
    assert_eq!(mode, SimMode::Spcr);
    assert_eq!(rig.cloths[0].mode, ClothMode::Spcr);
    let (mode, _) = SimMode::apply(None, &mut rig, false).unwrap();
    assert_eq!(mode, SimMode::Spcr);
    SimMode::apply(Some(SimMode::Fixed), &mut rig, false).unwrap();
    assert_eq!(rig.cloths[0].mode, ClothMode::Fixed);
    // The fixed and spcr modes give different motion on the same rig.
    let sk = skeleton();
    let run = |mode| {
        let mut r = RigSettings::from_toml_str(PANEL).unwrap();
        SimMode::apply(Some(mode), &mut r, false).unwrap();
        let mut sim = CharacterSim::new(sk.clone(), &r).unwrap();
        let root = sk.find("root").unwrap();
        for f in 0..30 {
            let mut locals = sk.rest().to_vec();
            let x = 0.2 * (f as f32 / 10.0).sin();
            locals[root] = Transform::from_translation(Vec3::new(x, 0.0, 0.0));
            sim.frame(&locals, Transform::IDENTITY, 1.0 / 60.0).unwrap();
        }
        sim.cloth_state().world_positions().to_vec()
    };
    let (a, b) = (run(SimMode::Fixed), run(SimMode::Spcr));
    assert!(a.iter().chain(&b).all(|p| p.is_finite()));
    let gap = a
        .iter()
        .zip(&b)
        .map(|(p, q)| (*p - *q).length())
        .fold(0.0, f32::max);
    assert!(
        gap > 1e-3,
        "fixed and spcr gave the same cloth ({gap} m apart)"
    );
}

/// Every point (world) at t = k/6 s, k = 1..=12, for `case`: through Tassel in `mode`, or
/// through the port of SPCR (`None`).
fn samples(case: Case, mode: Option<ClothMode>) -> Vec<Vec<DVec3>> {
    let sk = skeleton();
    let mut settings = rig(&case);
    if let Some(m) = mode {
        settings.cloths[0].mode = m;
    }
    let mut sim = CharacterSim::new(sk.clone(), &settings).unwrap();
    let frames = (2.0 * case.rate).round() as usize;
    let dt = (1.0 / case.rate) as f32;
    let per_sample = (case.rate / 6.0).round() as usize;
    let mut port: Option<Port> = None;
    let mut out = Vec::new();
    for f in 0..=frames {
        let t = f as f64 / case.rate;
        let step = if f == 0 { 0.0 } else { dt };
        let (locals, comp) = animated(&sk, case.motion, t);
        let frame = Frame::of(&sk, &models_of(&sk, &locals), comp);
        let points: Vec<DVec3> = match mode {
            Some(_) => {
                sim.frame(&locals, comp, step).unwrap();
                let w = sim.cloth_state().world_positions();
                w.iter().map(|p| p.as_dvec3()).collect()
            }
            None => {
                let port = port.get_or_insert_with(|| Port::new(case, &frame));
                port.evaluate(&frame, step);
                port.pts.iter().flatten().map(|p| p.pos).collect()
            }
        };
        if f > 0 && f % per_sample == 0 {
            out.push(points);
        }
    }
    out
}

fn largest_gap(a: &[Vec<DVec3>], b: &[Vec<DVec3>]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (*p - *q).length()))
        .fold(0.0, f64::max)
}

/// What `docs/cloth.md` says of the two modes, re-measured on the issue's panel (free, the
/// root swaying 0.2 m at 1 Hz or stepping 0.2 m, SPCR's defaults): Tassel's `fixed` is far
/// from SPCR's update at 60 Hz, and it is the one whose look does not depend on the frame
/// rate (swaying, its points at the same instants at 30, 60 and 144 Hz within a tenth of
/// SPCR's spread, which the port gives).
#[test]
fn fixed_keeps_its_look_across_frame_rates_where_spcr_does_not() {
    for motion in [Motion::Sin, Motion::Step] {
        let case = |rate| Case {
            motion,
            body: Body::None,
            surface: false,
            rate,
            extras: false,
        };
        let spcr: Vec<_> = [30.0, 60.0, 144.0].map(|r| samples(case(r), None)).into();
        let fixed: Vec<_> = [30.0, 60.0, 144.0]
            .map(|r| samples(case(r), Some(ClothMode::Fixed)))
            .into();
        let apart = largest_gap(&fixed[1], &spcr[1]);
        let spread =
            |s: &[Vec<Vec<DVec3>>]| largest_gap(&s[0], &s[1]).max(largest_gap(&s[1], &s[2]));
        let (spcr_spread, fixed_spread) = (spread(&spcr), spread(&fixed));
        println!(
            "{motion:?}: fixed vs SPCR at 60 Hz {:.2} cm; across 30/60/144 Hz SPCR moves {:.2} cm, fixed {:.4} cm",
            apart * 100.0,
            spcr_spread * 100.0,
            fixed_spread * 100.0
        );
        assert!(apart > 1e-3, "{motion:?}: fixed is {apart} m from SPCR");
        // A step is not a motion any frame rate shows alike (`fixed` spreads the jump over
        // the frame it falls in): only the sway is compared across rates.
        assert!(
            motion == Motion::Step || fixed_spread * 10.0 < spcr_spread,
            "{motion:?}: fixed spreads {fixed_spread} m across frame rates, SPCR {spcr_spread} m"
        );
    }
}

/// The written bones (character space) of every frame of `case` through the port with
/// `variant`.
fn port_output(case: Case, variant: Variant) -> Vec<Vec<DVec3>> {
    let sk = skeleton();
    let frames = (2.0 * case.rate).round() as usize;
    let dt = (1.0 / case.rate) as f32;
    let mut port: Option<Port> = None;
    let mut out = Vec::new();
    for f in 0..frames {
        let t = f as f64 / case.rate;
        let (locals, comp) = animated(&sk, case.motion, t);
        let frame = Frame::of(&sk, &models_of(&sk, &locals), comp);
        let port = port.get_or_insert_with(|| Port::with(case, &frame, variant));
        port.evaluate(&frame, if f == 0 { 0.0 } else { dt });
        out.push(port.out.iter().flatten().map(|(p, _)| *p).collect());
    }
    out
}

/// The table of `docs/cloth.md`: each of Tassel's `fixed` choices put alone into the port
/// in SPCR's place, on the issue's free panel at 60 Hz, swaying (0.2 m, 1 Hz) and stepping
/// (0.2 m): how far the written bones move from SPCR's. Each must move them (a switch
/// that moves nothing measures nothing).
#[test]
fn each_difference_from_spcr_measured_alone() {
    let rows: [(&str, Variant); 5] = [
        (
            "targets at each step's time",
            Variant {
                step_targets: true,
                ..Variant::default()
            },
        ),
        (
            "output blended from the last two steps",
            Variant {
                blend_output: true,
                ..Variant::default()
            },
        ),
        (
            "bones turned, not moved",
            Variant {
                turn_only: true,
                ..Variant::default()
            },
        ),
        (
            "constraints per chain, then per pair",
            Variant {
                tassel_order: true,
                ..Variant::default()
            },
        ),
        (
            "gravity and resistance as fixed",
            Variant {
                tassel_gravity: true,
                ..Variant::default()
            },
        ),
    ];
    for motion in [Motion::Sin, Motion::Step] {
        let case = Case {
            motion,
            body: Body::None,
            surface: false,
            rate: 60.0,
            extras: false,
        };
        let base = port_output(case, Variant::default());
        for (what, variant) in rows {
            let gap = largest_gap(&base, &port_output(case, variant));
            println!("{motion:?}: {what}: {:.2} cm", gap * 100.0);
            assert!(gap > 1e-5, "{motion:?}: {what} moved nothing ({gap} m)");
        }
    }
}

/// A hitch of a day, NaN in the pose and a teleport: the spcr cloth steps at most
/// `max_steps_per_frame` steps, gives an error for the NaN and no NaN after it, resets on
/// the teleport, and keeps stepping at the next ordinary frame (no stall from the time it
/// dropped).
#[test]
fn an_spcr_cloth_recovers_from_a_hitch_nan_and_a_teleport() {
    let sk = skeleton();
    let case = Case {
        motion: Motion::Sin,
        body: Body::Capsule,
        surface: true,
        rate: 60.0,
        extras: true,
    };
    let mut settings = rig(&case);
    settings.cloths[0].teleport_distance = 1.0;
    let mut sim = CharacterSim::new(sk.clone(), &settings).unwrap();
    let (locals, comp) = animated(&sk, Motion::Sin, 0.0);
    sim.frame(&locals, comp, 0.0).unwrap();
    let before: Vec<Vec3> = sim.cloth_state().world_positions().to_vec();
    for hitch in [1e3f32, 86_400.0, 1e6, 3e7] {
        sim.frame(&locals, comp, hitch).unwrap();
        // Each of the next ordinary frames still moves the cloth (steps are taken: the
        // dropped time leaves no debt behind).
        for k in 1..=5 {
            let (locals, comp) = animated(&sk, Motion::Sin, 0.1 * k as f64);
            let was: Vec<Vec3> = sim.cloth_state().world_positions().to_vec();
            sim.frame(&locals, comp, 1.0 / 60.0).unwrap();
            let now = sim.cloth_state().world_positions();
            assert!(
                now.iter().zip(&was).any(|(a, b)| (*a - *b).length() > 1e-6),
                "frame {k} after a hitch of {hitch} s took no step"
            );
            assert!(now.iter().all(|p| p.is_finite()));
        }
    }
    assert!(before.iter().all(|p| p.is_finite()));
    let mut bad = locals.clone();
    bad[sk.find("root").unwrap()].translation.x = f32::NAN;
    assert!(sim.frame(&bad, comp, 1.0 / 60.0).is_err());
    let (locals, comp) = animated(&sk, Motion::Sin, 0.7);
    let resets = sim.cloth_state().reset_count();
    let far = Transform::from_translation(comp.translation + Vec3::new(50.0, 0.0, 0.0));
    let pose = sim.frame(&locals, far, 1.0 / 60.0).unwrap().clone();
    assert_eq!(
        sim.cloth_state().reset_count(),
        resets + 1,
        "the teleport resets"
    );
    assert!(pose.models.iter().all(|m| m.is_finite()));
    // After the reset the points are on the animated pose, carried by the character.
    let w = sim.cloth_state().world_positions();
    assert!(w.iter().all(|p| p.x > 49.0), "the cloth came along: {w:?}");
}
