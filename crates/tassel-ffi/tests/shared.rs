//! Shared collision through the flat API and the C ABI (`tassel_shared_colliders`,
//! `tassel_set_shared_colliders`): one built-in character's body colliders handed to
//! another beside it whose chains use shared collision — the same bits through C as
//! through Rust's `CharacterSim` API, the floats decoding to the colliders Rust gives,
//! different motion than without them, and bad input refused by name.

mod common;

use common::last_error;
use std::ffi::CString;
use tassel::collide::Shape;
use tassel_ffi::abi::{
    tassel_character_free, tassel_character_load, tassel_frame, tassel_set_shared_colliders,
    tassel_shared_colliders,
};
use tassel_ffi::{FlatCharacter, FLOATS_PER_COLLIDER, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;
const C: usize = FLOATS_PER_COLLIDER;

/// The built-in rig (chains only), its chains using shared collision (`shared`), with a
/// `body` group of its torso and thighs.
fn rig(shared: bool) -> String {
    let mut rig = tassel::builtin::character().rig;
    rig.springs.clear();
    rig.cloths.clear();
    rig.ropes.clear();
    for c in &mut rig.chains {
        c.use_shared_collision = shared;
    }
    let names: Vec<String> = rig.colliders.iter().map(|c| c.name.clone()).collect();
    rig.collider_groups = vec![tassel::dynamics::ColliderGroupSettings {
        name: "body".into(),
        colliders: names,
    }];
    rig.to_toml_string().unwrap()
}

fn root(x: f32, f: usize) -> [f32; F] {
    let t = f as f32 / 60.0;
    [
        x + 0.1 * (3.0 * t).sin(),
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
        1.0,
        1.0,
        1.0,
        1.0,
    ]
}

#[test]
fn shared_colliders_through_the_c_abi_act_as_rusts() {
    let glb = common::builtin_glb();
    let (source_rig, target_rig, plain_rig) = (rig(false), rig(true), rig(false));
    let mut source = FlatCharacter::load(&glb, Some(&source_rig), None).unwrap();
    let mut rust = FlatCharacter::load(&glb, Some(&target_rig), None).unwrap();
    let mut plain = FlatCharacter::load(&glb, Some(&plain_rig), None).unwrap();
    let cstr = CString::new(target_rig).unwrap();
    // SAFETY: the bytes and the rig outlive the call; freed below.
    let c =
        unsafe { tassel_character_load(glb.as_ptr(), glb.len(), cstr.as_ptr(), std::ptr::null()) };
    assert!(!c.is_null(), "{}", last_error());
    let n = source.joint_count() * F;
    let mut rest = vec![0.0; n];
    source.rest_locals(&mut rest).unwrap();
    let src_ptr = {
        let r = CString::new(rig(false)).unwrap();
        // SAFETY: as above.
        let p =
            unsafe { tassel_character_load(glb.as_ptr(), glb.len(), r.as_ptr(), std::ptr::null()) };
        assert!(!p.is_null(), "{}", last_error());
        p
    };
    let body = CString::new("body").unwrap();
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    let mut moved = 0.0f32;
    let mut floats = vec![0.0f32; 64 * C];
    for f in 0..120 {
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        let mut out = rest.clone();
        source.frame(&root(0.0, f), &mut out, dt).unwrap();
        let mut out_c = vec![0.0; n];
        // SAFETY: buffers of `n` floats, the root of 10.
        let s = unsafe {
            tassel_frame(
                src_ptr,
                root(0.0, f).as_ptr(),
                rest.as_ptr(),
                out_c.as_mut_ptr(),
                n,
                dt,
            )
        };
        assert_eq!(s, 0, "{}", last_error());
        // Rust: the source's colliders into the target.
        let world = source.sim().shared_colliders(Some("body")).unwrap();
        rust.set_shared_colliders(&encode(&world)).unwrap();
        // C: asked for the count, then written, then set.
        // SAFETY: NULL out with capacity 0 asks for the count.
        let count =
            unsafe { tassel_shared_colliders(src_ptr, body.as_ptr(), std::ptr::null_mut(), 0) };
        assert_eq!(count as usize, world.len(), "{}", last_error());
        // SAFETY: `floats` holds 64 colliders.
        let wrote =
            unsafe { tassel_shared_colliders(src_ptr, body.as_ptr(), floats.as_mut_ptr(), 64) };
        assert_eq!(wrote, count);
        // The floats are the colliders Rust gives.
        for (w, x) in world.iter().zip(floats.chunks_exact(C)) {
            let t = w.transform;
            assert_eq!(
                &x[5..],
                &[
                    t.translation.x,
                    t.translation.y,
                    t.translation.z,
                    t.rotation.x,
                    t.rotation.y,
                    t.rotation.z,
                    t.rotation.w
                ]
            );
            match w.shape {
                Shape::Sphere { radius, .. } => assert_eq!((x[0], x[1]), (0.0, radius)),
                Shape::Capsule { radius, length } => assert_eq!(&x[..3], &[1.0, radius, length]),
                Shape::TaperedCapsule {
                    radius0,
                    radius1,
                    length,
                } => {
                    assert_eq!(&x[..4], &[2.0, radius0, radius1, length])
                }
                Shape::Box { half_extents: h } => assert_eq!(&x[..4], &[3.0, h.x, h.y, h.z]),
                Shape::Plane => assert_eq!(x[0], 4.0),
            }
        }
        // SAFETY: `count` colliders of 12 floats.
        let s = unsafe { tassel_set_shared_colliders(c, floats.as_ptr(), count as usize) };
        assert_eq!(s, 0, "{}", last_error());
        let r = root(0.22, f);
        let mut want = rest.clone();
        rust.frame(&r, &mut want, dt).unwrap();
        let mut without = rest.clone();
        plain.frame(&r, &mut without, dt).unwrap();
        let mut got = vec![0.0; n];
        // SAFETY: buffers of `n` floats, the root of 10.
        let s = unsafe { tassel_frame(c, r.as_ptr(), rest.as_ptr(), got.as_mut_ptr(), n, dt) };
        assert_eq!(s, 0, "{}", last_error());
        assert_eq!(bits(&got), bits(&want), "frame {f}: C vs Rust");
        for (a, b) in want.iter().zip(&without) {
            moved = moved.max((a - b).abs());
        }
    }
    assert!(moved > 1e-3, "the shared body moves the chains ({moved})");
    // Bad input: a group that does not exist, a bad kind, a negative radius, NULL.
    let nope = CString::new("nope").unwrap();
    // SAFETY: a live character, NULL out with capacity 0.
    assert_eq!(
        unsafe { tassel_shared_colliders(src_ptr, nope.as_ptr(), std::ptr::null_mut(), 0) },
        -1
    );
    assert!(last_error().contains("'nope'"), "{}", last_error());
    let mut bad = [0.0f32; C];
    bad[0] = 7.0;
    bad[11] = 1.0;
    // SAFETY: one collider of 12 floats.
    assert_eq!(
        unsafe { tassel_set_shared_colliders(c, bad.as_ptr(), 1) },
        -1
    );
    assert!(
        last_error().contains("shared collider 0") && last_error().contains("kind 7"),
        "{}",
        last_error()
    );
    bad[0] = 0.0;
    bad[1] = -1.0;
    // SAFETY: as above.
    assert_eq!(
        unsafe { tassel_set_shared_colliders(c, bad.as_ptr(), 1) },
        -1
    );
    assert!(
        last_error().contains("shared collider 0"),
        "{}",
        last_error()
    );
    // SAFETY: NULL data with a count is refused, never read.
    assert_eq!(
        unsafe { tassel_set_shared_colliders(c, std::ptr::null(), 1) },
        -1
    );
    // SAFETY: an empty set clears.
    assert_eq!(
        unsafe { tassel_set_shared_colliders(c, std::ptr::null(), 0) },
        0
    );
    // SAFETY: loaded above, freed once each.
    unsafe {
        tassel_character_free(c);
        tassel_character_free(src_ptr);
    }
}

/// The colliders as 12 floats each, written here from the layout the C header documents
/// (independently of the flat API's encoder).
fn encode(world: &[tassel::collide::PlacedCollider]) -> Vec<f32> {
    let mut floats = Vec::new();
    for w in world {
        let (k, p) = match w.shape {
            Shape::Sphere { radius, inside } => {
                (0.0, [radius, f32::from(u8::from(inside)), 0.0, 0.0])
            }
            Shape::Capsule { radius, length } => (1.0, [radius, length, 0.0, 0.0]),
            Shape::TaperedCapsule {
                radius0,
                radius1,
                length,
            } => (2.0, [radius0, radius1, length, 0.0]),
            Shape::Box { half_extents: h } => (3.0, [h.x, h.y, h.z, 0.0]),
            Shape::Plane => (4.0, [0.0; 4]),
        };
        let (t, r) = (w.transform.translation, w.transform.rotation);
        floats.extend_from_slice(&[k, p[0], p[1], p[2], p[3], t.x, t.y, t.z, r.x, r.y, r.z, r.w]);
    }
    floats
}
