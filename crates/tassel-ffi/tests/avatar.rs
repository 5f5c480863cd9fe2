//! `tassel_builtin_avatar`: the length first, then the bytes, the same as tassel-gltf's
//! `builtin_avatar`; the file loads through the ABI as a VRM character whose joints and
//! spring joints are the ones the avatar was made of; a short buffer gets the length only.

use std::ffi::{CStr, CString};
use tassel_ffi::abi::*;

#[test]
fn the_builtin_avatar_comes_out_whole_and_loads() {
    // SAFETY: NULL with capacity 0 only asks for the length.
    let len = unsafe { tassel_builtin_avatar(std::ptr::null_mut(), 0) };
    let want = tassel_gltf::builtin_avatar().unwrap();
    assert_eq!(len, want.len());
    // A buffer one byte short is left alone.
    let mut short = vec![7u8; len - 1];
    // SAFETY: `short` holds `len - 1` bytes.
    assert_eq!(
        unsafe { tassel_builtin_avatar(short.as_mut_ptr(), len - 1) },
        len
    );
    assert!(short.iter().all(|&b| b == 7));
    let mut bytes = vec![0u8; len];
    // SAFETY: `bytes` holds `len` bytes.
    assert_eq!(
        unsafe { tassel_builtin_avatar(bytes.as_mut_ptr(), len) },
        len
    );
    assert_eq!(bytes, want);
    // NULL with room claimed is an error, not a write.
    // SAFETY: NULL is allowed; it must be refused.
    assert_eq!(
        unsafe { tassel_builtin_avatar(std::ptr::null_mut(), len) },
        0
    );
    // SAFETY: after a failed call the message is set.
    let e = unsafe { CStr::from_ptr(tassel_last_error()) }
        .to_str()
        .unwrap();
    assert!(e.contains("out is NULL"), "{e}");

    let mode = CString::new("fixed").unwrap();
    // SAFETY: `bytes` is `len` bytes; no rig; a valid mode.
    let c = unsafe { tassel_character_load(bytes.as_ptr(), len, std::ptr::null(), mode.as_ptr()) };
    assert!(!c.is_null());
    let character = tassel::builtin::character();
    // SAFETY: `c` is live.
    unsafe {
        // Its 82 joints and the body's mesh node.
        assert_eq!(tassel_joint_count(c), character.skeleton.len() + 1);
        let springs = tassel::builtin::avatar::spring_bones(&character);
        let swinging: usize = springs.springs.iter().map(|s| s.joints.len()).sum();
        assert_eq!(tassel_simulated_joint_count(c), swinging);
        tassel_character_free(c);
    }
}
