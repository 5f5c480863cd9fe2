//! A controller level built from a glTF file's meshes: the mesh's placement and extent are
//! read independently from the file's JSON (node translation and scale, the POSITION
//! accessor's min/max) and the capsule must rest exactly on top.

mod common;

use glam::{Quat, Vec3};
use tassel::controller::{CharacterCapsule, ControllerSettings, Level};
use tassel::Transform;

#[test]
fn a_capsule_lands_on_a_mesh_read_from_gltf() {
    let Some(path) = common::testdata("vrm/sphere-collider.gltf") else {
        return;
    };
    let model = tassel_gltf::load(&path).unwrap();
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
    // Node 0 holds mesh 0 at the scene root: translation (0, 2, 0), scale 0.25; its
    // POSITION accessor says the mesh reaches y = max[1].
    let node = &json["nodes"][0];
    let mesh = node["mesh"].as_u64().unwrap() as usize;
    let position = json["meshes"][mesh]["primitives"][0]["attributes"]["POSITION"]
        .as_u64()
        .unwrap() as usize;
    let max_y = json["accessors"][position]["max"][1].as_f64().unwrap() as f32;
    let count = json["accessors"][position]["count"].as_u64().unwrap() as usize;
    let t = &node["translation"];
    let centre = Vec3::new(
        t[0].as_f64().unwrap() as f32,
        t[1].as_f64().unwrap() as f32,
        t[2].as_f64().unwrap() as f32,
    );
    let scale = node["scale"][1].as_f64().unwrap() as f32;
    let top = centre.y + scale * max_y;

    let instance = model
        .meshes
        .iter()
        .find(|m| m.node == 0)
        .expect("node 0's mesh");
    assert_eq!(instance.vertices.len(), count);
    let highest = instance
        .vertices
        .iter()
        .map(|v| v.y)
        .fold(f32::MIN, f32::max);
    assert!(
        (highest - top).abs() < 1e-5,
        "mesh top {highest}, file says {top}"
    );

    let level = Level::new(vec![instance.to_collider()]).unwrap();
    let capsule = CharacterCapsule::with_height(1.8, 0.3);
    let settings = ControllerSettings::default();
    let mut pos = Vec3::new(centre.x, top + 3.0, centre.z);
    let mut vy = 0.0f32;
    let dt = 1.0 / 60.0;
    let mut grounded = false;
    for _ in 0..180 {
        vy -= 9.81 * dt;
        let m = settings
            .move_shape(
                &level,
                &capsule,
                &Transform::from_translation(pos),
                Vec3::Y * vy * dt,
                dt,
            )
            .unwrap();
        pos += m.translation;
        grounded = m.grounded;
        if grounded {
            vy = 0.0;
        }
        assert!(
            level.capsule_penetration(capsule.radius, capsule.half_height, pos, Quat::IDENTITY)
                < 1e-4
        );
    }
    assert!(grounded);
    let bottom = pos.y - capsule.half_total_height();
    assert!(
        (bottom - top - settings.skin).abs() < 1e-3,
        "rests at {bottom}; the mesh top is {top}"
    );
}
