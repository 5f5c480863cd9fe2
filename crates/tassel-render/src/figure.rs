//! What one moment of a character looks like as lines: its bones (simulated ones marked),
//! virtual chain tips, and the colliders the solvers used, in world space.

use glam::Vec3;
use tassel::collide::{PlacedCollider, Shape};
use tassel::dynamics::vrm::PlacedVrmCollider;
use tassel::{CharacterSim, Transform};

/// A collider's outline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outline {
    /// A sphere.
    Sphere {
        /// Centre.
        center: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A capsule between two cap centres.
    Capsule {
        /// One end.
        a: Vec3,
        /// The other end.
        b: Vec3,
        /// Radius.
        radius: f32,
    },
    /// A tapered capsule: two end balls of different radii and the cone between them.
    TaperedCapsule {
        /// One end.
        a: Vec3,
        /// The other end.
        b: Vec3,
        /// Radius at `a`.
        radius_a: f32,
        /// Radius at `b`.
        radius_b: f32,
    },
    /// An oriented box: its eight corners.
    Box {
        /// Corners, index bits (x, y, z) = (1, 2, 4) set for the + side.
        corners: [Vec3; 8],
    },
    /// A plane through `point` with `normal` (drawn as a short stretch of its trace).
    Plane {
        /// A point of the plane.
        point: Vec3,
        /// Unit normal.
        normal: Vec3,
    },
}

impl Outline {
    /// Points that bound the outline (for framing).
    pub fn extent(&self) -> Vec<(Vec3, f32)> {
        match *self {
            Outline::Sphere { center, radius } => vec![(center, radius)],
            Outline::Capsule { a, b, radius } => vec![(a, radius), (b, radius)],
            Outline::TaperedCapsule {
                a,
                b,
                radius_a,
                radius_b,
            } => vec![(a, radius_a), (b, radius_b)],
            Outline::Box { corners } => corners.iter().map(|c| (*c, 0.0)).collect(),
            Outline::Plane { point, .. } => vec![(point, 0.0)],
        }
    }
}

/// A bone drawn from `from` to `to`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bone {
    /// Parent joint position.
    pub from: Vec3,
    /// Child joint position (or a virtual tip).
    pub to: Vec3,
    /// The child is moved by a solver (drawn highlighted).
    pub simulated: bool,
}

/// A spring joint's swing limit (`VRMC_springBone_limit`): its boundary at the bone's
/// length from the joint, world space.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LimitOutline {
    /// The joint the bone turns about.
    pub joint: Vec3,
    /// The boundary, walked around (the cone's rim, the hinge's arc, the spherical box).
    pub rim: Vec<Vec3>,
}

/// One moment of a character, world space.
///
/// ```
/// use tassel::{builtin, CharacterSim, Transform};
/// use tassel_render::{contact_sheet, Figure, SIMULATED_COLOR};
///
/// let c = builtin::character();
/// let mut sim = CharacterSim::new(c.skeleton.clone(), &c.rig).unwrap();
/// sim.frame(c.skeleton.rest(), Transform::IDENTITY, 0.0).unwrap();
/// let figure = Figure::from_sim(&sim, &Transform::IDENTITY, 0.0);
/// // A bone to every joint that has a parent (and to the chains' virtual tips).
/// let parented = (0..c.skeleton.len()).filter(|&j| c.skeleton.parent(j).is_some()).count();
/// assert!(figure.bones.len() >= parented);
/// assert!(figure.bones.iter().any(|b| b.simulated));
/// // Side and front views; the simulated bones in their colour.
/// let sheet = contact_sheet(&[figure], "AT REST");
/// assert!(sheet.pixels().chunks(3).any(|p| p == SIMULATED_COLOR));
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Figure {
    /// Bones.
    pub bones: Vec<Bone>,
    /// Colliders.
    pub colliders: Vec<Outline>,
    /// Swing limits of VRM spring joints.
    pub limits: Vec<LimitOutline>,
    /// Seconds into the clip (for labels).
    pub time: f32,
}

impl Figure {
    /// The last frame of `sim` under the character transform `component`: every bone
    /// whose parent is a joint, chain tips without a joint, the colliders of the VRM
    /// springs, the chains (or, without chains, the cloths), and the VRM springs' swing
    /// limits.
    pub fn from_sim(sim: &CharacterSim, component: &Transform, time: f32) -> Figure {
        let sk = sim.skeleton();
        let models = &sim.pose().models;
        let simulated = sim.simulated_joints();
        let world = |p: Vec3| component.transform_point(p);
        let mut bones = Vec::new();
        for j in 0..sk.len() {
            if let Some(p) = sk.parent(j) {
                bones.push(Bone {
                    from: world(models[p].translation),
                    to: world(models[j].translation),
                    simulated: simulated.binary_search(&j).is_ok(),
                });
            }
        }
        let chains = sim.chains();
        let out = sim.chain_state().output_positions();
        for p in 0..chains.point_count() {
            let info = chains.point(p);
            if let (None, Some(parent)) = (info.joint, info.parent) {
                if let (Some(a), Some(b)) = (out.get(parent), out.get(p)) {
                    bones.push(Bone {
                        from: world(*a),
                        to: world(*b),
                        simulated: true,
                    });
                }
            }
        }
        let mut colliders: Vec<Outline> = sim
            .vrm_state()
            .placed_colliders()
            .iter()
            .map(|c| match *c {
                PlacedVrmCollider::Sphere { center, radius, .. } => {
                    Outline::Sphere { center, radius }
                }
                PlacedVrmCollider::Capsule {
                    head, tail, radius, ..
                } => Outline::Capsule {
                    a: head,
                    b: tail,
                    radius,
                },
                PlacedVrmCollider::Plane { point, normal } => Outline::Plane { point, normal },
            })
            .collect();
        if chains.point_count() > 0 {
            for c in sim.chain_state().placed_colliders() {
                let placed = PlacedCollider {
                    shape: c.shape,
                    transform: *component * c.transform,
                };
                colliders.push(outline(&placed));
            }
        } else {
            colliders.extend(sim.cloth_state().placed_colliders().iter().map(outline));
        }
        // `vrm_limit_outline` is under the sim's own transform: re-placed here under
        // `component`, as the bones are.
        let to_here = *component * sim.component().inverse();
        let limits = sim
            .vrm()
            .links
            .iter()
            .filter_map(|l| {
                let rim = sim.vrm_limit_outline(l.joint, 24)?;
                Some(LimitOutline {
                    joint: world(models[l.joint].translation),
                    rim: rim
                        .into_iter()
                        .map(|p| to_here.transform_point(p))
                        .collect(),
                })
            })
            .collect();
        Figure {
            bones,
            colliders,
            limits,
            time,
        }
    }
}

/// The outline of a rig collider placed in world space.
pub fn outline(c: &PlacedCollider) -> Outline {
    let t = &c.transform;
    match c.shape {
        Shape::Sphere { radius, .. } => Outline::Sphere {
            center: t.translation,
            radius,
        },
        Shape::Capsule { radius, length } => {
            let axis = t.rotation * Vec3::Y * (0.5 * length);
            Outline::Capsule {
                a: t.translation - axis,
                b: t.translation + axis,
                radius,
            }
        }
        Shape::TaperedCapsule {
            radius0,
            radius1,
            length,
        } => {
            // `radius0` at the +Y end.
            let axis = t.rotation * Vec3::Y * (0.5 * length);
            Outline::TaperedCapsule {
                a: t.translation + axis,
                b: t.translation - axis,
                radius_a: radius0,
                radius_b: radius1,
            }
        }
        Shape::Box { half_extents } => {
            let mut corners = [Vec3::ZERO; 8];
            for (i, c) in corners.iter_mut().enumerate() {
                let s = Vec3::new(
                    if i & 1 != 0 { 1.0 } else { -1.0 },
                    if i & 2 != 0 { 1.0 } else { -1.0 },
                    if i & 4 != 0 { 1.0 } else { -1.0 },
                );
                *c = t.translation + t.rotation * (s * half_extents);
            }
            Outline::Box { corners }
        }
        Shape::Plane => Outline::Plane {
            point: t.translation,
            normal: t.rotation * Vec3::Y,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use tassel::dynamics::vrm::{
        VrmJoint, VrmLimit, VrmLimitShape, VrmOptions, VrmSpring, VrmSpringBones, VrmTail,
    };
    use tassel::dynamics::RigSettings;
    use tassel::SkeletonBuilder;

    /// A hair bone 0.2 m long hanging along −Z of its joint, limited to a 0.3 rad cone:
    /// the figure's limit is a ring of points 0.2 m from the joint, each 0.3 rad from the
    /// rest bone (the cone's rim, computed by hand: the frame turns +Y onto the bone axis).
    #[test]
    fn a_cone_limit_is_drawn_as_its_rim_at_the_bone_length() {
        let mut b = SkeletonBuilder::new();
        b.add("root", None, Transform::IDENTITY);
        b.add("hair", Some(0), Transform::from_translation(Vec3::Y));
        let (sk, _) = b.build().unwrap();
        let bones = VrmSpringBones {
            springs: vec![VrmSpring {
                name: "hair".into(),
                joints: vec![VrmJoint {
                    joint: 1,
                    tail: VrmTail::Local(Vec3::new(0.0, 0.0, -0.2)),
                    limit: Some(VrmLimit::new(VrmLimitShape::Cone { angle: 0.3 })),
                    ..Default::default()
                }],
                ..Default::default()
            }],
            ..Default::default()
        };
        let mut sim =
            CharacterSim::with_vrm(sk, &RigSettings::default(), &bones, VrmOptions::default())
                .unwrap();
        let at = Transform::from_translation(Vec3::new(2.0, 0.0, 0.0));
        let rest = sim.skeleton().rest().to_vec();
        sim.frame(&rest, at, 0.0).unwrap();
        let figure = Figure::from_sim(&sim, &at, 0.0);
        assert_eq!(figure.limits.len(), 1);
        let l = &figure.limits[0];
        assert!((l.joint - Vec3::new(2.0, 1.0, 0.0)).length() < 1e-6);
        assert!(l.rim.len() >= 24);
        for p in &l.rim {
            let d = *p - l.joint;
            assert!((d.length() - 0.2).abs() < 1e-5, "{d}");
            assert!((d.angle_between(Vec3::NEG_Z) - 0.3).abs() < 1e-4, "{d}");
        }
    }
}
