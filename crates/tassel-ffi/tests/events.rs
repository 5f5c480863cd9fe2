//! Animation events through the flat API and the C ABI (`tassel_event`): a force of the
//! rig file switched on by `tassel:enable_force` acts as the same force on from the
//! start, bit for bit; the game's own events pass; a bad one is -1 with an error that
//! names it.

mod common;

use common::last_error;
use std::ffi::CString;
use tassel_ffi::abi::{
    tassel_character_free, tassel_character_load, tassel_event, tassel_frame,
    tassel_start_settings_override, tassel_stop_settings_override,
};
use tassel_ffi::{FlatCharacter, FLOATS_PER_JOINT};

const F: usize = FLOATS_PER_JOINT;

/// The built-in character's chains as a GLB and a rig file with a gust on (`on`) or off.
fn builtin_with_gust(on: bool) -> (Vec<u8>, String) {
    let glb = common::builtin_glb();
    let mut rig = tassel::builtin::character().rig;
    rig.springs.clear();
    rig.cloths.clear();
    rig.ropes.clear();
    let mut gust = tassel::builtin::level::gust();
    gust.enabled = on;
    rig.external_forces = vec![gust];
    (glb, rig.to_toml_string().unwrap())
}

fn root(f: usize) -> [f32; F] {
    let t = f as f32 / 60.0;
    [
        0.3 * (2.0 * t).sin(),
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
fn events_switch_the_rig_files_forces_through_the_flat_api_and_the_c_abi() {
    let (glb, on) = builtin_with_gust(true);
    let (_, off) = builtin_with_gust(false);
    let mut reference = FlatCharacter::load(&glb, Some(&on), None).unwrap();
    let mut plain = FlatCharacter::load(&glb, Some(&off), None).unwrap();
    let mut flat = FlatCharacter::load(&glb, Some(&off), None).unwrap();
    assert!(flat.apply_event("tassel:enable_force gust").unwrap());
    assert!(!flat.apply_event("footstep").unwrap());
    let rig = CString::new(off).unwrap();
    // SAFETY: the bytes and the rig outlive the call; the character is freed below.
    let c =
        unsafe { tassel_character_load(glb.as_ptr(), glb.len(), rig.as_ptr(), std::ptr::null()) };
    assert!(!c.is_null(), "{}", last_error());
    let event = |text: &str| {
        let text = CString::new(text).unwrap();
        // SAFETY: a live character and a NUL-terminated string.
        unsafe { tassel_event(c, text.as_ptr()) }
    };
    assert_eq!(event("tassel:enable_force gust"), 1);
    assert_eq!(event("jump_landed"), 0);
    assert_eq!(event("tassel:enable_force breeze"), -1);
    assert!(last_error().contains("'breeze'"), "{}", last_error());
    assert_eq!(event("tassel:set_alpha"), -1);
    assert!(
        last_error().contains("tassel:set_alpha"),
        "{}",
        last_error()
    );
    // SAFETY: NULL is refused with an error, never read.
    assert_eq!(unsafe { tassel_event(c, std::ptr::null()) }, -1);

    let n = reference.joint_count() * F;
    let mut rest = vec![0.0; n];
    reference.rest_locals(&mut rest).unwrap();
    let (mut moved, mut differs) = (0.0f32, false);
    for f in 0..90 {
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        let r = root(f);
        let mut want = rest.clone();
        reference.frame(&r, &mut want, dt).unwrap();
        let mut got = rest.clone();
        flat.frame(&r, &mut got, dt).unwrap();
        let mut without = rest.clone();
        plain.frame(&r, &mut without, dt).unwrap();
        let mut abi = vec![0.0; n];
        // SAFETY: buffers of `n` floats, the root of 10; no overlap.
        let status = unsafe { tassel_frame(c, r.as_ptr(), rest.as_ptr(), abi.as_mut_ptr(), n, dt) };
        assert_eq!(status, 0, "{}", last_error());
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&got), bits(&want), "frame {f}: flat event vs rig");
        assert_eq!(bits(&abi), bits(&want), "frame {f}: C ABI event vs rig");
        differs |= bits(&without) != bits(&want);
        for (a, b) in want.iter().zip(&without) {
            moved = moved.max((a - b).abs());
        }
    }
    assert!(
        differs && moved > 1e-3,
        "the gust moves the chains ({moved})"
    );
    // SAFETY: loaded above, freed once.
    unsafe { tassel_character_free(c) };
}

/// A timed settings override through the C ABI acts as the same override through the
/// flat API and as its animation event, bit for bit; it changes the motion; stopping by
/// handle answers 1 then 0; bad values and chains are -1 with the problem named.
#[test]
fn settings_overrides_through_the_c_abi_act_as_the_flat_api_and_the_event() {
    let (glb, off) = builtin_with_gust(false);
    let mut plain = FlatCharacter::load(&glb, Some(&off), None).unwrap();
    let mut flat = FlatCharacter::load(&glb, Some(&off), None).unwrap();
    let mut by_event = FlatCharacter::load(&glb, Some(&off), None).unwrap();
    let rig = CString::new(off).unwrap();
    // SAFETY: the bytes and the rig outlive the call; the character is freed below.
    let c =
        unsafe { tassel_character_load(glb.as_ptr(), glb.len(), rig.as_ptr(), std::ptr::null()) };
    assert!(!c.is_null(), "{}", last_error());
    let scales = [0.5f32, 3.0, 0.5, 0.5, 1.0, 1.0];
    // SAFETY: a live character, 6 floats, NULL chain (every chain).
    let handle = unsafe {
        tassel_start_settings_override(c, scales.as_ptr(), 1.0, 0.2, 0.3, std::ptr::null())
    };
    assert!(handle > 0, "{}", last_error());
    let h = flat
        .start_settings_override(scales, 1.0, 0.2, 0.3, None)
        .unwrap();
    assert!(by_event
        .apply_event(
            "tassel:override x damping=0.5 stiffness=3 world_damping_location=0.5 \
             world_damping_rotation=0.5 duration=1 blend_in=0.2 blend_out=0.3"
        )
        .unwrap());
    // Bad input: -1 and the problem named; nothing queued.
    let bad = [1.0f32, -2.0, 1.0, 1.0, 1.0, 1.0];
    // SAFETY: as above.
    let r =
        unsafe { tassel_start_settings_override(c, bad.as_ptr(), 1.0, 0.2, 0.3, std::ptr::null()) };
    assert_eq!(r, -1);
    assert!(last_error().contains("stiffness"), "{}", last_error());
    let tail = CString::new("no_such_chain").unwrap();
    // SAFETY: as above, a NUL-terminated chain name.
    let r =
        unsafe { tassel_start_settings_override(c, scales.as_ptr(), 1.0, 0.2, 0.3, tail.as_ptr()) };
    assert_eq!(r, -1);
    assert!(last_error().contains("'no_such_chain'"), "{}", last_error());
    // SAFETY: NULL scales are refused, never read.
    let r = unsafe {
        tassel_start_settings_override(c, std::ptr::null(), 1.0, 0.2, 0.3, std::ptr::null())
    };
    assert_eq!(r, -1);

    let n = flat.joint_count() * F;
    let mut rest = vec![0.0; n];
    flat.rest_locals(&mut rest).unwrap();
    let mut moved = 0.0f32;
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for f in 0..90 {
        if f == 40 {
            // SAFETY: a live character.
            assert_eq!(unsafe { tassel_stop_settings_override(c, handle, 0.25) }, 1);
            assert!(flat.stop_settings_override(h, 0.25));
            assert!(by_event.apply_event("tassel:stop_override x 0.25").unwrap());
        }
        let dt = if f == 0 { 0.0 } else { 1.0 / 60.0 };
        let r = root(f);
        let mut want = rest.clone();
        flat.frame(&r, &mut want, dt).unwrap();
        let mut evented = rest.clone();
        by_event.frame(&r, &mut evented, dt).unwrap();
        let mut without = rest.clone();
        plain.frame(&r, &mut without, dt).unwrap();
        let mut abi = vec![0.0; n];
        // SAFETY: buffers of `n` floats, the root of 10; no overlap.
        let status = unsafe { tassel_frame(c, r.as_ptr(), rest.as_ptr(), abi.as_mut_ptr(), n, dt) };
        assert_eq!(status, 0, "{}", last_error());
        assert_eq!(bits(&abi), bits(&want), "frame {f}: C ABI vs flat");
        assert_eq!(bits(&evented), bits(&want), "frame {f}: event vs flat");
        for (a, b) in want.iter().zip(&without) {
            moved = moved.max((a - b).abs());
        }
    }
    assert!(moved > 1e-3, "the override moves the chains ({moved})");
    // Stopped at once and ended: the handle is no one's now.
    // SAFETY: a live character.
    assert_eq!(unsafe { tassel_stop_settings_override(c, handle, 0.0) }, 0);
    // SAFETY: loaded above, freed once.
    unsafe { tassel_character_free(c) };
}
