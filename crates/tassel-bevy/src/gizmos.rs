//! Debug drawing: colliders, chain points and VRM springs of every character, with Bevy's
//! gizmos (after transform propagation, as of the frame just stepped).

use crate::character::TasselCharacter;
use bevy::app::{App, Plugin, PostUpdate};
use bevy::color::Color;
use bevy::ecs::prelude::*;
use bevy::gizmos::prelude::Gizmos;
use bevy::math::{Isometry3d, Quat, Vec3};
use bevy::transform::TransformSystems;
use tassel::collide::Shape;
use tassel::dynamics::vrm::PlacedVrmCollider;

/// Draws each character's colliders (orange), chain points and links (cyan) and VRM
/// spring bones from joint to tail (magenta) with their swing limits (yellow). Needs Bevy's gizmo plugin (in
/// `DefaultPlugins` with the `bevy_gizmos` feature).
#[derive(Default)]
pub struct TasselGizmosPlugin;

impl Plugin for TasselGizmosPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(PostUpdate, draw.after(TransformSystems::Propagate));
    }
}

const COLLIDER: Color = Color::srgb(1.0, 0.55, 0.1);
const CHAIN: Color = Color::srgb(0.2, 0.9, 1.0);
const SPRING: Color = Color::srgb(1.0, 0.3, 0.9);
const LIMIT: Color = Color::srgb(1.0, 0.85, 0.2);

fn draw(mut gizmos: Gizmos, characters: Query<&TasselCharacter>) {
    // Characters stepped in a crowd have no sim of their own to draw from
    // (`SecondaryMotion::without_crowd` keeps one).
    for sim in characters.iter().filter_map(TasselCharacter::sim) {
        let component = sim.component();
        // Chains: points (model space) and the links to their parents.
        let chains = sim.chains();
        let out = sim.chain_state().output_positions();
        for p in 0..chains.point_count().min(out.len()) {
            let here = component.transform_point(out[p]);
            if let Some(parent) = chains.point(p).parent {
                gizmos.line(here, component.transform_point(out[parent]), CHAIN);
            }
        }
        for c in sim.chain_state().placed_colliders() {
            let world = component * c.transform;
            shape(&mut gizmos, &c.shape, world.translation, world.rotation);
        }
        // VRM springs: joint to tail, and the colliders (world space).
        let vrm = sim.vrm();
        for link in &vrm.links {
            if let (Some(joint), Some(tail)) =
                (sim.bone_world(link.joint), sim.vrm_tail_world(link.joint))
            {
                gizmos.line(joint.translation, tail, SPRING);
                // A limit (`VRMC_springBone_limit`): its boundary at the bone's length,
                // and a few lines from the joint to it.
                if let Some(rim) = sim.vrm_limit_outline(link.joint, 24) {
                    for p in rim.iter().step_by(6) {
                        gizmos.line(joint.translation, *p, LIMIT);
                    }
                    gizmos.linestrip(rim, LIMIT);
                }
            }
        }
        for c in sim.vrm_state().placed_colliders() {
            match *c {
                PlacedVrmCollider::Sphere { center, radius, .. } => {
                    gizmos.sphere(Isometry3d::from_translation(center), radius, COLLIDER);
                }
                PlacedVrmCollider::Capsule {
                    head, tail, radius, ..
                } => capsule(&mut gizmos, head, tail, radius, radius),
                _ => {}
            }
        }
    }
}

fn shape(gizmos: &mut Gizmos, shape: &Shape, at: Vec3, rotation: Quat) {
    match *shape {
        Shape::Sphere { radius, .. } => {
            gizmos.sphere(Isometry3d::new(at, rotation), radius, COLLIDER);
        }
        Shape::Capsule { radius, length } => {
            let half = rotation * Vec3::Y * (0.5 * length);
            capsule(gizmos, at - half, at + half, radius, radius);
        }
        Shape::TaperedCapsule {
            radius0,
            radius1,
            length,
        } => {
            // `radius0` at the +Y end.
            let half = rotation * Vec3::Y * (0.5 * length);
            capsule(gizmos, at + half, at - half, radius0, radius1);
        }
        Shape::Box { half_extents } => {
            gizmos.cube(
                bevy::prelude::Transform::from_translation(at)
                    .with_rotation(rotation)
                    .with_scale(2.0 * half_extents),
                COLLIDER,
            );
        }
        _ => {}
    }
}

/// A capsule from `a` (radius `ra`) to `b` (radius `rb`): the end balls and four lines
/// along its side (a tapered capsule's radius changes linearly along the axis).
fn capsule(gizmos: &mut Gizmos, a: Vec3, b: Vec3, ra: f32, rb: f32) {
    gizmos.sphere(Isometry3d::from_translation(a), ra, COLLIDER);
    gizmos.sphere(Isometry3d::from_translation(b), rb, COLLIDER);
    let axis = (b - a).normalize_or(Vec3::Y);
    let side = axis.any_orthonormal_vector();
    let up = axis.cross(side);
    for offset in [side, -side, up, -up] {
        gizmos.line(a + offset * ra, b + offset * rb, COLLIDER);
    }
}
