//! The C ABI over [`FlatCrowd`]: many characters of one kind, one call a frame.

use super::{
    character, check_ptr, copy_indices, floats, floats_mut, guard, overlaps, set_error,
    TasselCharacter,
};
use crate::crowd::FlatCrowd;
use std::ffi::{c_char, CStr};

/// A crowd of characters of one kind (opaque): free it with `tassel_crowd_free`.
pub struct TasselCrowd {
    flat: FlatCrowd,
}

/// # Safety
/// `c` is NULL or a live crowd.
unsafe fn crowd<'a>(c: *const TasselCrowd) -> Result<&'a FlatCrowd, String> {
    // SAFETY: the caller's promise: NULL or a live crowd.
    unsafe { c.as_ref() }
        .map(|c| &c.flat)
        .ok_or_else(|| "the crowd is NULL".to_string())
}

/// # Safety
/// `c` is NULL or a live crowd, used by this thread alone.
unsafe fn crowd_mut<'a>(c: *mut TasselCrowd) -> Result<&'a mut FlatCrowd, String> {
    // SAFETY: the caller's promise: NULL or a live crowd, not shared during the call.
    unsafe { c.as_mut() }
        .map(|c| &mut c.flat)
        .ok_or_else(|| "the crowd is NULL".to_string())
}

/// An empty crowd of characters like `kind` (its file, rig and mode; `kind` itself is not
/// a member and may be freed after). Characters of a kind with VRM spring bones only, or
/// bone chains only, step side by side in SIMD lanes; any other kind one after another.
/// A character added starts from its pose on its first frame (as after `tassel_reset`).
/// NULL on error.
///
/// # Safety
/// `kind` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_new(kind: *const TasselCharacter) -> *mut TasselCrowd {
    guard("tassel_crowd_new", std::ptr::null_mut(), || {
        // SAFETY: the caller's promise.
        let kind = unsafe { character(kind) }?;
        Ok(Box::into_raw(Box::new(TasselCrowd {
            flat: FlatCrowd::new(&kind.flat),
        })))
    })
}

/// Frees a crowd (NULL: nothing happens).
///
/// # Safety
/// `c` is NULL or a live crowd, not used after this call.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_free(c: *mut TasselCrowd) {
    if !c.is_null() {
        // SAFETY: a live crowd from `Box::into_raw`, given back once.
        drop(unsafe { Box::from_raw(c) });
    }
}

/// Adds a character to the crowd: its index (the characters are numbered 0, 1, … in the
/// order added), or -1 for NULL.
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_add(c: *mut TasselCrowd) -> isize {
    guard("tassel_crowd_add", -1, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { crowd_mut(c) }?.add() as isize)
    })
}

/// Removes character `i`: the last character takes its index (and carries on exactly as
/// it would have). 0 = ok, -1 = error (NULL, no such character).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_remove(c: *mut TasselCrowd, i: usize) -> i32 {
    guard("tassel_crowd_remove", -1, || {
        // SAFETY: the caller's promise.
        unsafe { crowd_mut(c) }?.swap_remove(i).map(|_| 0)
    })
}

/// Number of characters (0 for NULL).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_len(c: *const TasselCrowd) -> usize {
    guard("tassel_crowd_len", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { crowd(c) }?.len())
    })
}

/// Promises that character `i`'s animated pose in the next frame's input is, bit for
/// bit, the last frame's (its transform may change): a character no animation moves,
/// only carried. For the next frame only. A VRM crowd in `fixed` mode then steps a lane
/// group of such characters on the pose it kept instead of reading their input again
/// (the same result, at less cost); elsewhere the mark changes nothing. A false mark
/// steps on last frame's pose. 0 = ok, -1 = error (no such character).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_mark_pose_unchanged(c: *mut TasselCrowd, i: usize) -> i32 {
    guard("tassel_crowd_mark_pose_unchanged", -1, || {
        // SAFETY: the caller's promise.
        unsafe { crowd_mut(c) }?.mark_pose_unchanged(i).map(|_| 0)
    })
}

/// Character `i` starts again from its pose on the next frame (a cut, a respawn, a
/// teleport). 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_reset(c: *mut TasselCrowd, i: usize) -> i32 {
    guard("tassel_crowd_reset", -1, || {
        // SAFETY: the caller's promise.
        unsafe { crowd_mut(c) }?.reset(i).map(|_| 0)
    })
}

/// How many joints a crowd frame reads for each character (0 for NULL).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_read_joint_count(c: *const TasselCrowd) -> usize {
    guard("tassel_crowd_read_joint_count", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { crowd(c) }?.read_joints().len())
    })
}

/// The joints a crowd frame reads (the simulated joints, their tails, colliders and
/// ancestors), ascending, into `out` (exactly `tassel_crowd_read_joint_count` entries).
/// 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live crowd; `out` is NULL or points to `len` entries.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_read_joints(
    c: *const TasselCrowd,
    out: *mut usize,
    len: usize,
) -> i32 {
    guard("tassel_crowd_read_joints", -1, || {
        // SAFETY: the caller's promises.
        unsafe { copy_indices(crowd(c)?.read_joints(), out, len, "read joints") }
    })
}

/// How many joints a crowd frame writes for each character (0 for NULL).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_written_joint_count(c: *const TasselCrowd) -> usize {
    guard("tassel_crowd_written_joint_count", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { crowd(c) }?.written_joints().len())
    })
}

/// The joints a crowd frame writes (the simulated joints), ascending, into `out`
/// (exactly `tassel_crowd_written_joint_count` entries). 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live crowd; `out` is NULL or points to `len` entries.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_written_joints(
    c: *const TasselCrowd,
    out: *mut usize,
    len: usize,
) -> i32 {
    guard("tassel_crowd_written_joints", -1, || {
        // SAFETY: the caller's promises.
        unsafe { copy_indices(crowd(c)?.written_joints(), out, len, "written joints") }
    })
}

/// One frame of every character of the crowd. `roots`: each character's world transform,
/// 10 floats a character (`roots_len` floats); `locals`: each character's animated local
/// transforms of the read joints (`tassel_crowd_read_joints`, in that order), 10 floats a
/// joint, character after character; `out`: each character's simulated local transforms
/// of the written joints, likewise. `dt`: seconds since the last frame, ≥ 0. `out` must
/// not overlap the inputs.
///
/// 0 = every character stepped. 1 = some characters' input was bad (NaN, a rotation that
/// is not a unit quaternion): those were held — not stepped, their part of `out` not
/// written — and the others stepped as they would have; `tassel_crowd_held` lists them and
/// `tassel_last_error()` gives the first one's message. -1 = error (NULL, a wrong length,
/// overlapping buffers, a bad `dt`): nothing changed.
///
/// # Safety
/// `c` is NULL or a live crowd; each buffer is NULL or holds the floats its length says.
#[no_mangle]
#[allow(clippy::too_many_arguments)]
pub unsafe extern "C" fn tassel_crowd_frame(
    c: *mut TasselCrowd,
    roots: *const f32,
    roots_len: usize,
    locals: *const f32,
    locals_len: usize,
    out: *mut f32,
    out_len: usize,
    dt: f32,
) -> i32 {
    let stepped = guard("tassel_crowd_frame", None, || {
        // SAFETY: the caller's promises; `out` is refused when it overlaps an input, so no
        // two references alias.
        unsafe {
            let cr = crowd_mut(c)?;
            check_ptr(out, out_len, "out")?;
            for (p, n, what) in [(roots, roots_len, "roots"), (locals, locals_len, "locals")] {
                if !p.is_null() && overlaps(p, n, out, out_len) {
                    return Err(format!("out overlaps {what}"));
                }
            }
            let roots = floats(roots, roots_len, "roots")?;
            let locals = floats(locals, locals_len, "locals")?;
            let out = floats_mut(out, out_len, "out")?;
            Ok(Some(cr.frame(roots, locals, out, dt)?))
        }
    });
    match stepped {
        Some(true) => 0,
        Some(false) => {
            // SAFETY: the frame above ran, so `c` is a live crowd.
            if let Some((i, e)) = unsafe { crowd(c) }.ok().and_then(|c| c.held().first()) {
                set_error(&format!("tassel_crowd_frame: character {i}: {e}"));
            }
            1
        }
        None => -1,
    }
}

/// How many characters the last frame held (0 for NULL).
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_held_count(c: *const TasselCrowd) -> usize {
    guard("tassel_crowd_held_count", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { crowd(c) }?.held().len())
    })
}

/// The characters the last frame held, ascending, into `out` (exactly
/// `tassel_crowd_held_count` entries). 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live crowd; `out` is NULL or points to `len` entries.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_held(
    c: *const TasselCrowd,
    out: *mut usize,
    len: usize,
) -> i32 {
    guard("tassel_crowd_held", -1, || {
        // SAFETY: the caller's promises.
        let held: Vec<usize> = unsafe { crowd(c) }?
            .held()
            .iter()
            .map(|(i, _)| *i)
            .collect();
        // SAFETY: the caller's promise.
        unsafe { copy_indices(&held, out, len, "held characters") }
    })
}

/// How the crowd steps, static: "vrm" (VRM spring bones side by side in SIMD lanes),
/// "chains" (bone chains side by side) or "characters" (one after another). NULL for
/// NULL.
///
/// # Safety
/// `c` is NULL or a live crowd.
#[no_mangle]
pub unsafe extern "C" fn tassel_crowd_kind(c: *const TasselCrowd) -> *const c_char {
    guard("tassel_crowd_kind", std::ptr::null(), || {
        // SAFETY: the caller's promise.
        let kind: &CStr = match unsafe { crowd(c) }?.kind() {
            "vrm" => c"vrm",
            "chains" => c"chains",
            _ => c"characters",
        };
        Ok(kind.as_ptr())
    })
}
