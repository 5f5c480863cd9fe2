//! `tassel_character_new` / `FlatCharacter::from_skeleton`: a character from a skeleton
//! the caller owns. For every VRM file of ../shared/testdata (and the built-in avatar, Fox
//! with its rig, the built-in character with its rig), the joints, parents and rest pose a
//! loaded character reports, plus the file's own springs JSON (cut from the file), give a
//! character whose frames are the loaded one's bit for bit, in every mode. Bad skeletons
//! are refused with a message naming the joint or the key.

mod common;

use common::{builtin_glb, vrm_files};
use std::ffi::{CStr, CString};
use tassel_ffi::{FlatCharacter, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;

/// The glTF JSON of a GLB, or of a .gltf's text.
fn json_of(bytes: &[u8]) -> serde_json::Value {
    if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        serde_json::from_slice(&bytes[20..20 + len]).unwrap()
    } else {
        serde_json::from_slice(bytes).unwrap()
    }
}

/// The file's spring bones as the constructor takes them: the `VRMC_springBone` object,
/// else VRM 0.x's `secondaryAnimation`, as JSON text.
fn springs_json(bytes: &[u8]) -> Option<String> {
    let json = json_of(bytes);
    let ext = &json["extensions"];
    ext.get("VRMC_springBone")
        .or_else(|| ext.get("VRM").and_then(|v| v.get("secondaryAnimation")))
        .map(|v| v.to_string())
}

/// What a loaded character says of its skeleton: names, parents (-1 for roots), rest.
fn skeleton_of(c: &FlatCharacter) -> (Vec<String>, Vec<i64>, Vec<f32>) {
    let n = c.joint_count();
    let names = (0..n)
        .map(|j| c.joint_name(j).unwrap().to_string())
        .collect();
    let parents = (0..n)
        .map(|j| c.joint_parent(j).map_or(-1, |p| p as i64))
        .collect();
    let mut rest = vec![0.0; n * F];
    c.rest_locals(&mut rest).unwrap();
    (names, parents, rest)
}

/// 240 frames (a sway, a turning joint, a hitch at 120) through both: the same bits.
fn same_frames(what: &str, a: &mut FlatCharacter, b: &mut FlatCharacter) {
    let n = a.joint_count();
    assert_eq!(b.joint_count(), n, "{what}");
    let mut rest = vec![0.0; n * F];
    a.rest_locals(&mut rest).unwrap();
    let turn = a.read_joints().first().copied().unwrap_or(0);
    let mut moved = false;
    for f in 0..240 {
        let t = f as f32 / 60.0;
        let root = [
            0.3 * (2.0 * t).sin(),
            0.0,
            0.1 * t,
            0.0,
            (0.4 * t).sin() * 0.3,
            0.0,
            1.0,
            1.0,
            1.0,
            1.0,
        ];
        let mut root = root;
        let len = (root[4] * root[4] + 1.0f32).sqrt();
        root[4] /= len;
        root[6] /= len;
        let mut la = rest.clone();
        let (s, co) = (0.3 * (3.0 * t).sin()).sin_cos();
        la[turn * F + 3] = s;
        la[turn * F + 6] = co;
        let mut lb = la.clone();
        let dt = if f == 120 { 0.2 } else { 1.0 / 60.0 };
        let ra = a.frame(&root, &mut la, dt);
        let rb = b.frame(&root, &mut lb, dt);
        assert_eq!(ra.is_ok(), rb.is_ok(), "{what}: frame {f}");
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&la), bits(&lb), "{what}: frame {f}");
        moved |= la.iter().zip(&rest).any(|(x, r)| (x - r).abs() > 1e-3);
    }
    assert!(moved, "{what}: nothing moved");
}

fn both(what: &str, bytes: &[u8], rig: Option<&str>, mode: &str) {
    let mut loaded = FlatCharacter::load(bytes, rig, Some(mode)).unwrap();
    let (names, parents, rest) = skeleton_of(&loaded);
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    let springs = springs_json(bytes);
    let mut made =
        FlatCharacter::from_skeleton(&names, &parents, &rest, rig, springs.as_deref(), Some(mode))
            .unwrap_or_else(|e| panic!("{what} {mode}: {e}"));
    assert_eq!(made.simulated_joints(), loaded.simulated_joints(), "{what}");
    assert_eq!(made.read_joints(), loaded.read_joints(), "{what}");
    same_frames(&format!("{what} {mode}"), &mut loaded, &mut made);
}

#[test]
fn a_skeleton_and_its_springs_step_as_the_file_does() {
    for path in vrm_files() {
        let bytes = std::fs::read(&path).unwrap();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        for mode in ["fixed", "spec", "three-vrm"] {
            both(&name, &bytes, None, mode);
        }
    }
    let avatar = tassel_gltf::builtin_avatar().unwrap();
    for mode in ["fixed", "spec", "three-vrm"] {
        both("the built-in avatar", &avatar, None, mode);
    }
    // Rigs alone: the built-in character's chains, cloth, rope and springs; Fox's tail.
    let rig = tassel::builtin::character().rig.to_toml_string().unwrap();
    both(
        "the built-in character",
        &builtin_glb(),
        Some(&rig),
        "fixed",
    );
    let fox =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/testdata/gltf/Fox.glb");
    if let Ok(bytes) = std::fs::read(&fox) {
        let rig = std::fs::read_to_string(
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/rigs/fox.toml"),
        )
        .unwrap();
        for mode in ["fixed", "classic"] {
            both("Fox", &bytes, Some(&rig), mode);
        }
    }
}

use std::path::PathBuf;

/// The C function itself, on the built-in avatar: the same frames as its load.
#[test]
fn the_c_function_takes_the_same_skeleton() {
    use tassel_ffi::abi::*;
    let bytes = tassel_gltf::builtin_avatar().unwrap();
    let loaded = FlatCharacter::load(&bytes, None, Some("fixed")).unwrap();
    let (names, parents, rest) = skeleton_of(&loaded);
    let names: Vec<CString> = names
        .iter()
        .map(|n| CString::new(n.as_str()).unwrap())
        .collect();
    let name_ptrs: Vec<*const std::ffi::c_char> = names.iter().map(|n| n.as_ptr()).collect();
    let parents: Vec<i32> = parents.iter().map(|&p| p as i32).collect();
    let springs = CString::new(springs_json(&bytes).unwrap()).unwrap();
    let n = names.len();
    // SAFETY: every buffer is as long as the count given; strings are NUL-terminated.
    unsafe {
        let c = tassel_character_new(
            name_ptrs.as_ptr(),
            parents.as_ptr(),
            rest.as_ptr(),
            n,
            std::ptr::null(),
            springs.as_ptr(),
            std::ptr::null(),
        );
        assert!(!c.is_null(), "{:?}", CStr::from_ptr(tassel_last_error()));
        let l = tassel_character_load(
            bytes.as_ptr(),
            bytes.len(),
            std::ptr::null(),
            std::ptr::null(),
        );
        assert_eq!(tassel_joint_count(c), tassel_joint_count(l));
        assert_eq!(CStr::from_ptr(tassel_mode(c)), c"fixed");
        let root = [0.2f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        let (mut a, mut b) = (vec![0.0f32; n * F], vec![0.0f32; n * F]);
        for _ in 0..30 {
            assert_eq!(
                tassel_frame(
                    c,
                    root.as_ptr(),
                    rest.as_ptr(),
                    a.as_mut_ptr(),
                    a.len(),
                    1.0 / 60.0
                ),
                0
            );
            assert_eq!(
                tassel_frame(
                    l,
                    root.as_ptr(),
                    rest.as_ptr(),
                    b.as_mut_ptr(),
                    b.len(),
                    1.0 / 60.0
                ),
                0
            );
            assert_eq!(a, b);
        }
        tassel_character_free(c);
        tassel_character_free(l);
        // NULL names: an error, no character.
        let none = tassel_character_new(
            std::ptr::null(),
            parents.as_ptr(),
            rest.as_ptr(),
            n,
            std::ptr::null(),
            springs.as_ptr(),
            std::ptr::null(),
        );
        assert!(none.is_null());
        let e = CStr::from_ptr(tassel_last_error()).to_str().unwrap();
        assert!(
            e.contains("tassel_character_new") && e.contains("NULL"),
            "{e}"
        );
    }
}

#[test]
fn bad_skeletons_are_refused_by_name() {
    let id = [0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
    let rest3: Vec<f32> = id.iter().chain(&id).chain(&id).copied().collect();
    let rig = "[[chain]]\nname = \"c\"\nroot = \"a\"\n";
    // (what, names, parents, rest, springs JSON, the message's part)
    type Case<'a> = (
        &'a str,
        Vec<&'a str>,
        Vec<i64>,
        Vec<f32>,
        Option<&'a str>,
        &'a str,
    );
    let cases: Vec<Case> = vec![
        (
            "a cycle",
            vec!["a", "b", "c"],
            vec![-1, 2, 1],
            rest3.clone(),
            None,
            "cycle through joint",
        ),
        (
            "a parent out of range",
            vec!["a", "b", "c"],
            vec![-1, 0, 7],
            rest3.clone(),
            None,
            "joint 2 ('c'): parent 7",
        ),
        (
            "its own parent",
            vec!["a", "b", "c"],
            vec![-1, 1, 1],
            rest3.clone(),
            None,
            "joint 1 ('b'): parent 1",
        ),
        (
            "a repeated name",
            vec!["a", "b", "a"],
            vec![-1, 0, 1],
            rest3.clone(),
            None,
            "joint 2 repeats the name 'a'",
        ),
        (
            "an empty name",
            vec!["a", "", "c"],
            vec![-1, 0, 1],
            rest3.clone(),
            None,
            "joint 1 has no name",
        ),
        (
            "too few parents",
            vec!["a", "b", "c"],
            vec![-1, 0],
            rest3.clone(),
            None,
            "2 parents for 3 joints",
        ),
        (
            "a short rest",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            rest3[..20].to_vec(),
            None,
            "rest holds 20 floats",
        ),
        (
            "a NaN rest",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            {
                let mut r = rest3.clone();
                r[12] = f32::NAN;
                r
            },
            None,
            "joint 1 ('b'): the rest transform",
        ),
        (
            "a zero rotation",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            {
                let mut r = rest3.clone();
                r[26] = 0.0;
                r
            },
            None,
            "joint 2 ('c'): the rest transform",
        ),
        (
            "springs that are not JSON",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            rest3.clone(),
            Some("{springs"),
            "springs JSON",
        ),
        (
            "springs of neither kind",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            rest3.clone(),
            Some("{\"x\": 1}"),
            "neither a VRMC_springBone",
        ),
        (
            "a spring joint out of range",
            vec!["a", "b", "c"],
            vec![-1, 0, 1],
            rest3.clone(),
            Some(
                "{\"specVersion\":\"1.0\",\"springs\":[{\"joints\":[{\"node\":0},{\"node\":9}]}]}",
            ),
            "node",
        ),
    ];
    for (what, names, parents, rest, springs, want) in cases {
        let e = FlatCharacter::from_skeleton(&names, &parents, &rest, Some(rig), springs, None)
            .map(|_| ())
            .unwrap_err();
        assert!(e.contains(want), "{what}: {e}");
    }
    // No joints; no rig and no springs.
    assert!(
        FlatCharacter::from_skeleton(&[], &[], &[], Some(rig), None, None)
            .unwrap_err()
            .contains("no joints")
    );
    let e = FlatCharacter::from_skeleton(&["a", "b", "c"], &[-1, 0, 1], &rest3, None, None, None)
        .map(|_| ())
        .unwrap_err();
    assert!(e.contains("rig file"), "{e}");
    // Parents after their children (any order) and a rotation a little off unit: taken.
    let mut rest = rest3.clone();
    rest[26] = 1.01;
    let c =
        FlatCharacter::from_skeleton(&["c", "b", "a"], &[1, 2, -1], &rest, Some(rig), None, None)
            .unwrap();
    assert_eq!(c.joint_parent(0), Some(1));
    assert_eq!(c.joint_parent(2), None);
}

/// VRM 0.x `secondaryAnimation` (no test file has one): the built-in skeleton written as a
/// GLB with a bone group over the ponytail and a lock (each walked to its leaf, which gets
/// a virtual tail) and a head collider group, loaded, against the same skeleton and the
/// same JSON given to the constructor.
#[test]
fn vrm0_secondary_animation_steps_as_the_file_does() {
    let c = tassel::builtin::character();
    let sk = &c.skeleton;
    let node = |name: &str| sk.find(name).unwrap();
    let sa = serde_json::json!({
        "boneGroups": [{
            "comment": "hair",
            "stiffiness": 0.8,
            "gravityPower": 0.3,
            "gravityDir": { "x": 0.0, "y": -1.0, "z": 0.0 },
            "dragForce": 0.4,
            "center": -1,
            "hitRadius": 0.02,
            "bones": [node("ponytail_0"), node("lock_l_0")],
            "colliderGroups": [0]
        }],
        "colliderGroups": [{
            "node": node("head"),
            "colliders": [{ "offset": { "x": 0.0, "y": 0.09, "z": 0.0 }, "radius": 0.11 }]
        }]
    });
    let mut source = tassel_gltf::ExportSource::from_skeleton(sk, tassel_gltf::BoneMesh::None);
    source.json["extensionsUsed"] = serde_json::json!(["VRM"]);
    source.json["extensions"] = serde_json::json!({ "VRM": { "secondaryAnimation": sa } });
    let glb = tassel_gltf::export_glb(&source, &[]).unwrap();
    let loaded = FlatCharacter::load(&glb, None, None).unwrap();
    // 5 ponytail joints + 2 lock joints, each group walked to its leaf.
    assert_eq!(loaded.simulated_joints().len(), 6 + 3);
    for mode in ["fixed", "spec", "three-vrm"] {
        both("VRM 0.x on the built-in skeleton", &glb, None, mode);
    }
}
