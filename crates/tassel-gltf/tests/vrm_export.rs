//! Writing VRM 1.0: the built-in avatar read back by the importer (an independent reader,
//! tested on the VRM files of ../shared/testdata), its humanoid checked against the
//! skeleton's names, the Khronos validator on the file, and bad avatars refused.

mod common;

use tassel::builtin::{self, avatar};
use tassel::dynamics::vrm::{VrmJoint, VrmSpringBones, VrmTail};
use tassel::glam;
use tassel_gltf::{builtin_avatar, load_slice, BoneMesh, ExportSource, VrmAvatar, VrmVersion};

fn json_of(glb: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

/// The springs with every joint index replaced by its name.
fn named(b: &VrmSpringBones, name: impl Fn(usize) -> String) -> String {
    let mut out = String::new();
    for s in &b.springs {
        out += &format!("{} groups {:?}\n", s.name, s.collider_groups);
        for j in &s.joints {
            let VrmTail::Joint(t) = j.tail else {
                panic!("a local tail")
            };
            out += &format!(
                "  {} -> {} r{} k{} g{} {:?} d{}\n",
                name(j.joint),
                name(t),
                j.hit_radius,
                j.stiffness,
                j.gravity_power,
                j.gravity_dir,
                j.drag_force
            );
        }
    }
    for c in &b.colliders {
        out += &format!("{} {:?}\n", name(c.joint), c.shape);
    }
    for g in &b.collider_groups {
        out += &format!("{} {:?}\n", g.name, g.colliders);
    }
    out
}

#[test]
fn the_builtin_avatar_reads_back_as_the_springs_it_was_made_of() {
    let c = builtin::character();
    let glb = builtin_avatar().unwrap();
    let model = load_slice(&glb, None, "avatar.vrm").unwrap();
    let vrm = model.vrm.as_ref().expect("spring bones read back");
    assert_eq!(vrm.version, VrmVersion::V1);
    let want = avatar::spring_bones(&c);
    assert_eq!(
        named(&vrm.springs, |j| model.skeleton.name(j).to_string()),
        named(&want, |j| c.skeleton.name(j).to_string())
    );
    // 82 joints and the body's mesh node; one skin over the joints (a primitive per material).
    assert_eq!(c.skeleton.len(), 82);
    assert_eq!(model.skeleton.len(), 83);
    assert_eq!(model.skins.len(), 1);
    assert!(!model.meshes.is_empty());
    let swinging: usize = vrm.springs.springs.iter().map(|s| s.joints.len()).sum();
    assert!(swinging >= 16, "{swinging} spring joints");

    // The humanoid names the nodes of the joints HUMANOID lists.
    let json = json_of(&glb);
    let bones = json["extensions"]["VRMC_vrm"]["humanoid"]["humanBones"]
        .as_object()
        .unwrap();
    assert_eq!(bones.len(), avatar::HUMANOID.len());
    for (bone, joint) in avatar::HUMANOID {
        let node = bones[bone]["node"].as_u64().unwrap() as usize;
        assert_eq!(json["nodes"][node]["name"], joint, "{bone}");
    }
    assert_eq!(json["extensions"]["VRMC_vrm"]["specVersion"], "1.0");
    let used = json["extensionsUsed"].as_array().unwrap();
    assert!(used.iter().any(|u| u == "VRMC_vrm") && used.iter().any(|u| u == "VRMC_springBone"));
    // A spring's last entry is its tail alone.
    let ponytail = &json["extensions"]["VRMC_springBone"]["springs"][0];
    let last = ponytail["joints"].as_array().unwrap().last().unwrap();
    assert_eq!(
        json["nodes"][last["node"].as_u64().unwrap() as usize]["name"],
        "ponytail_5"
    );
    assert!(last.get("stiffness").is_none());

    let file = std::env::temp_dir().join(format!("tassel-avatar-{}.vrm", std::process::id()));
    std::fs::write(&file, &glb).unwrap();
    if let Some((errors, report)) = common::validate(&file) {
        assert_eq!(errors, 0, "{report}");
    }
    let _ = std::fs::remove_file(file);
}

fn small() -> (ExportSource, VrmAvatar) {
    let c = builtin::character();
    let source = ExportSource::from_skeleton(&c.skeleton, BoneMesh::None);
    let humanoid = avatar::HUMANOID
        .iter()
        .map(|(b, j)| (b.to_string(), c.skeleton.find(j).unwrap()))
        .collect();
    let avatar = VrmAvatar {
        name: "t".into(),
        authors: vec!["t".into()],
        license_url: String::new(),
        humanoid,
        springs: avatar::spring_bones(&c),
    };
    (source, avatar)
}

#[test]
fn bad_avatars_are_refused_by_name_and_leave_the_document_as_it_was() {
    type Spoil = Box<dyn Fn(&mut VrmAvatar)>;
    let cases: Vec<(&str, Spoil)> = vec![
        (
            "leftFoot is missing",
            Box::new(|a| a.humanoid.retain(|(b, _)| b != "leftFoot")),
        ),
        (
            "are both node",
            Box::new(|a| a.humanoid[1].1 = a.humanoid[0].1),
        ),
        ("node 999", Box::new(|a| a.humanoid[0].1 = 999)),
        ("author", Box::new(|a| a.authors.clear())),
        (
            "follow one another",
            Box::new(|a| {
                let j: &mut VrmJoint = &mut a.springs.springs[0].joints[0];
                j.tail = VrmTail::Joint(0);
            }),
        ),
        (
            "virtual tail",
            Box::new(|a| {
                let s = &mut a.springs.springs[0];
                let last = s.joints.len() - 1;
                s.joints[last].tail = VrmTail::Local(glam::Vec3::Y);
            }),
        ),
        (
            "is negative",
            Box::new(|a| a.springs.springs[1].joints[0].hit_radius = -0.1),
        ),
        (
            "not finite",
            Box::new(|a| a.springs.springs[1].joints[0].stiffness = f32::NAN),
        ),
        (
            "collider group 99",
            Box::new(|a| a.springs.springs[1].collider_groups.push(99)),
        ),
    ];
    for (want, spoil) in cases {
        let (mut source, mut avatar) = small();
        let before = source.json.clone();
        spoil(&mut avatar);
        let e = source.add_vrm(&avatar).unwrap_err().to_string();
        assert!(e.contains(want), "{want}: {e}");
        assert_eq!(source.json, before, "{want}: the document changed");
    }
    let (mut source, avatar) = small();
    source.add_vrm(&avatar).unwrap();
}
