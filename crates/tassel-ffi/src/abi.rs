//! The C ABI over [`FlatCharacter`] and [`crate::FlatCrowd`]: the functions of
//! `include/tassel.h`.
//!
//! Every function catches panics (none crosses the boundary: a panic is reported as an
//! error) and takes NULL pointers, wrong lengths, misaligned or overlapping buffers and
//! invalid UTF-8 as errors: `-1` (or NULL, or 0 where noted) and a message for
//! [`tassel_last_error`]. A failed call changes nothing.
//!
//! What the caller promises (the `# Safety` of each function): a non-NULL pointer points
//! to what the header says, valid for the length given, for the time of the call; a
//! character pointer came from a load and was not freed; a character is used by one
//! thread at a time.
#![allow(unsafe_code)]

mod crowd;

pub use crowd::*;

use crate::flat::{FlatCharacter, FLOATS_PER_JOINT};
use std::cell::RefCell;
use std::ffi::{c_char, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// A loaded character (opaque): free it with `tassel_character_free`.
pub struct TasselCharacter {
    flat: FlatCharacter,
    /// The joints' names as C strings (borrowed by `tassel_joint_name`).
    names: Vec<CString>,
    mode: CString,
}

thread_local! {
    static LAST_ERROR: RefCell<Option<CString>> = const { RefCell::new(None) };
}

fn set_error(message: &str) {
    let c = CString::new(message.replace('\0', " ")).unwrap_or_default();
    LAST_ERROR.with(|e| *e.borrow_mut() = Some(c));
}

/// Runs `f`; an error or a panic sets this thread's last error and gives `failed`.
fn guard<T>(function: &str, failed: T, f: impl FnOnce() -> Result<T, String>) -> T {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(v)) => v,
        Ok(Err(message)) => {
            set_error(&format!("{function}: {message}"));
            failed
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            set_error(&format!(
                "{function}: internal error (a panic, caught; please report it): {what}"
            ));
            failed
        }
    }
}

/// The character behind `c`, or an error for NULL.
///
/// # Safety
/// `c` is NULL or a live character from a load.
unsafe fn character<'a>(c: *const TasselCharacter) -> Result<&'a TasselCharacter, String> {
    // SAFETY: the caller's promise: NULL or a live character.
    unsafe { c.as_ref() }.ok_or_else(|| "the character is NULL".to_string())
}

/// # Safety
/// `c` is NULL or a live character from a load, used by this thread alone.
unsafe fn character_mut<'a>(c: *mut TasselCharacter) -> Result<&'a mut TasselCharacter, String> {
    // SAFETY: the caller's promise: NULL or a live character, not shared during the call.
    unsafe { c.as_mut() }.ok_or_else(|| "the character is NULL".to_string())
}

/// An optional UTF-8 C string.
///
/// # Safety
/// `s` is NULL or a NUL-terminated string.
unsafe fn opt_str<'a>(s: *const c_char, what: &str) -> Result<Option<&'a str>, String> {
    if s.is_null() {
        return Ok(None);
    }
    // SAFETY: the caller's promise: a NUL-terminated string.
    let c = unsafe { CStr::from_ptr(s) };
    c.to_str()
        .map(Some)
        .map_err(|e| format!("{what} is not UTF-8: {e}"))
}

/// A float buffer of `len` floats, checked for NULL and alignment.
///
/// # Safety
/// `p` is NULL or points to `len` floats.
unsafe fn floats<'a>(p: *const f32, len: usize, what: &str) -> Result<&'a [f32], String> {
    check_ptr(p, len, what)?;
    // SAFETY: non-NULL, aligned, and `len` floats by the caller's promise.
    Ok(unsafe { std::slice::from_raw_parts(p, len) })
}

/// # Safety
/// `p` is NULL or points to `len` floats no other live reference reads or writes.
unsafe fn floats_mut<'a>(p: *mut f32, len: usize, what: &str) -> Result<&'a mut [f32], String> {
    check_ptr(p, len, what)?;
    // SAFETY: non-NULL, aligned, and `len` floats by the caller's promise.
    Ok(unsafe { std::slice::from_raw_parts_mut(p, len) })
}

fn check_ptr(p: *const f32, len: usize, what: &str) -> Result<(), String> {
    if p.is_null() {
        return Err(format!("{what} is NULL"));
    }
    if !(p as usize).is_multiple_of(std::mem::align_of::<f32>()) {
        return Err(format!("{what} is not aligned to 4 bytes"));
    }
    if len > isize::MAX as usize / std::mem::size_of::<f32>() {
        return Err(format!("{what}: {len} floats is not a length"));
    }
    Ok(())
}

/// Whether the `a_len` floats at `a` and the `b_len` floats at `b` share memory.
fn overlaps(a: *const f32, a_len: usize, b: *const f32, b_len: usize) -> bool {
    let bytes = |n: usize| n * std::mem::size_of::<f32>();
    let (a, b) = (a as usize, b as usize);
    a_len > 0 && b_len > 0 && a < b + bytes(b_len) && b < a + bytes(a_len)
}

fn new_character(flat: FlatCharacter) -> *mut TasselCharacter {
    let names = (0..flat.joint_count())
        .map(|j| {
            let name = flat.joint_name(j).unwrap_or_default().replace('\0', " ");
            CString::new(name).unwrap_or_default()
        })
        .collect();
    let mode = CString::new(flat.mode()).unwrap_or_default();
    Box::into_raw(Box::new(TasselCharacter { flat, names, mode }))
}

/// Loads a character from the bytes of a GLB, VRM or glTF file (a `.gltf` whose buffers
/// are external files is an error naming the URI; data: URIs work; see
/// `tassel_character_load_file`). `rig_toml` (may be NULL) is a rig file's text: chains,
/// springs, cloths, ropes; without it the file's VRM spring bones run (a file without
/// them is an error). `mode` (may be NULL) is "fixed", "spec", "three-vrm", "classic",
/// "kawaii" or "spcr"; NULL as `tassel simulate` without `--mode`: "fixed", unless the rig
/// sets its chains to "classic" or "kawaii" (or, without chains, its first cloth to "spcr").
///
/// The character is left as `tassel simulate` has it before its frame 1 (a zero-length
/// frame at the rest pose, at the origin). NULL on error: `tassel_last_error()` says why.
///
/// # Safety
/// `bytes` points to `len` bytes; `rig_toml` and `mode` are NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn tassel_character_load(
    bytes: *const u8,
    len: usize,
    rig_toml: *const c_char,
    mode: *const c_char,
) -> *mut TasselCharacter {
    guard("tassel_character_load", std::ptr::null_mut(), || {
        if bytes.is_null() {
            return Err("bytes is NULL".into());
        }
        // SAFETY: non-NULL; `len` bytes by the caller's promise.
        let data = unsafe { std::slice::from_raw_parts(bytes, len) };
        // SAFETY: NULL or NUL-terminated, by the caller's promise.
        let (rig, mode) = unsafe { (opt_str(rig_toml, "rig_toml")?, opt_str(mode, "mode")?) };
        Ok(new_character(FlatCharacter::load(data, rig, mode)?))
    })
}

/// A character from a skeleton the caller owns (an engine's or a tool's: Blender's
/// armature, Godot's `Skeleton3D`, Unreal's `USkeleton`, a Unity `Transform` tree), not a
/// file: `joint_count` joints with their `names` (UTF-8, NUL-terminated, unique, not
/// empty), `parents` (-1 for a root; any order, no cycle) and `rest` local transforms
/// (`joint_count * 10` floats, as `tassel_frame`), plus a rig file's text (`rig_toml`),
/// and/or VRM spring bones as JSON text (`springs_json`: a `VRMC_springBone` 1.0 extension
/// object, or VRM 0.x's `secondaryAnimation`, with node indices into this joint list),
/// and a mode (NULL: `fixed`, as `tassel_character_load`). Every buffer of the other
/// calls keeps this joint order. A VRM 0.x bone group walks a joint's children in this
/// list's order. The character is left as `tassel_character_load` leaves one.
///
/// NULL on error; `tassel_last_error()` names the joint or the key.
///
/// # Safety
/// `names` points to `joint_count` NUL-terminated strings; `parents` to `joint_count`
/// entries; `rest` to `joint_count * 10` floats; `rig_toml`, `springs_json` and `mode` are
/// NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn tassel_character_new(
    names: *const *const c_char,
    parents: *const i32,
    rest: *const f32,
    joint_count: usize,
    rig_toml: *const c_char,
    springs_json: *const c_char,
    mode: *const c_char,
) -> *mut TasselCharacter {
    guard("tassel_character_new", std::ptr::null_mut(), || {
        if names.is_null() || parents.is_null() {
            return Err("names or parents is NULL".into());
        }
        if joint_count > tassel::MAX_JOINTS {
            return Err(format!(
                "{joint_count} joints; at most {} are taken",
                tassel::MAX_JOINTS
            ));
        }
        if !(names as usize).is_multiple_of(std::mem::align_of::<*const c_char>())
            || !(parents as usize).is_multiple_of(std::mem::align_of::<i32>())
        {
            return Err("names or parents is not aligned".into());
        }
        // SAFETY: non-NULL, aligned, `joint_count` entries by the caller's promise.
        let (name_ptrs, parent_list) = unsafe {
            (
                std::slice::from_raw_parts(names, joint_count),
                std::slice::from_raw_parts(parents, joint_count),
            )
        };
        let mut joint_names = Vec::with_capacity(joint_count);
        for (j, &p) in name_ptrs.iter().enumerate() {
            // SAFETY: NULL or NUL-terminated, by the caller's promise.
            let name = unsafe { opt_str(p, &format!("the name of joint {j}"))? }
                .ok_or_else(|| format!("the name of joint {j} is NULL"))?;
            joint_names.push(name);
        }
        let parents: Vec<i64> = parent_list.iter().map(|&p| p as i64).collect();
        // SAFETY: `joint_count * 10` floats by the caller's promise (checked for NULL
        // and alignment).
        let rest = unsafe { floats(rest, joint_count * FLOATS_PER_JOINT, "rest")? };
        // SAFETY: NULL or NUL-terminated, by the caller's promise.
        let (rig, springs, mode) = unsafe {
            (
                opt_str(rig_toml, "rig_toml")?,
                opt_str(springs_json, "springs_json")?,
                opt_str(mode, "mode")?,
            )
        };
        Ok(new_character(FlatCharacter::from_skeleton(
            &joint_names,
            &parents,
            rest,
            rig,
            springs,
            mode,
        )?))
    })
}

/// As `tassel_character_load`, from a file's path (UTF-8): a `.gltf` may read its
/// buffers beside it.
///
/// # Safety
/// `path` is a NUL-terminated string; `rig_toml` and `mode` are NULL or NUL-terminated.
#[no_mangle]
pub unsafe extern "C" fn tassel_character_load_file(
    path: *const c_char,
    rig_toml: *const c_char,
    mode: *const c_char,
) -> *mut TasselCharacter {
    guard("tassel_character_load_file", std::ptr::null_mut(), || {
        // SAFETY: NULL or NUL-terminated, by the caller's promise.
        let (path, rig, mode) = unsafe {
            (
                opt_str(path, "path")?.ok_or("path is NULL")?,
                opt_str(rig_toml, "rig_toml")?,
                opt_str(mode, "mode")?,
            )
        };
        Ok(new_character(FlatCharacter::load_file(
            std::path::Path::new(path),
            rig,
            mode,
        )?))
    })
}

/// A new character of the same kind as `c`, as a load of the same file, rig and mode
/// would make it (fresh state, the rest pose), sharing `c`'s compiled rig: nothing is
/// parsed or compiled again, and copies of one avatar keep one rig in memory (see
/// `FlatCharacter::fresh_copy`). `c`'s own state is not copied, and `c` may be freed
/// before its copies. NULL on error (`tassel_last_error` says why). Free it with
/// `tassel_character_free`.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_character_copy(c: *const TasselCharacter) -> *mut TasselCharacter {
    guard("tassel_character_copy", std::ptr::null_mut(), || {
        // SAFETY: the caller's promise.
        let flat = unsafe { character(c) }?.flat.fresh_copy()?;
        Ok(new_character(flat))
    })
}

/// Frees a character (NULL: nothing happens).
///
/// # Safety
/// `c` is NULL or a live character from a load, not used after this call.
#[no_mangle]
pub unsafe extern "C" fn tassel_character_free(c: *mut TasselCharacter) {
    if !c.is_null() {
        // SAFETY: a live character from `Box::into_raw`, given back once.
        drop(unsafe { Box::from_raw(c) });
    }
}

/// How many joints: every node of the file, in the file's node order. 0 for NULL.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_joint_count(c: *const TasselCharacter) -> usize {
    // SAFETY: the caller's promise.
    guard("tassel_joint_count", 0, || {
        Ok(unsafe { character(c) }?.flat.joint_count())
    })
}

/// Joint `joint`'s name, UTF-8, borrowed: valid while the character lives. NULL for
/// NULL or a joint that does not exist.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_joint_name(
    c: *const TasselCharacter,
    joint: usize,
) -> *const c_char {
    guard("tassel_joint_name", std::ptr::null(), || {
        // SAFETY: the caller's promise.
        let ch = unsafe { character(c) }?;
        ch.names
            .get(joint)
            .map(|n| n.as_ptr())
            .ok_or_else(|| no_joint(ch, joint))
    })
}

fn no_joint(ch: &TasselCharacter, joint: usize) -> String {
    format!(
        "joint {joint} does not exist (the character has {})",
        ch.flat.joint_count()
    )
}

/// Joint `joint`'s parent joint; -1 for a root; -2 for NULL or a joint that does not
/// exist.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_joint_parent(c: *const TasselCharacter, joint: usize) -> i32 {
    guard("tassel_joint_parent", -2, || {
        // SAFETY: the caller's promise.
        let ch = unsafe { character(c) }?;
        if joint >= ch.flat.joint_count() {
            return Err(no_joint(ch, joint));
        }
        Ok(ch.flat.joint_parent(joint).map_or(-1, |p| p as i32))
    })
}

/// The rest pose (the file's node transforms) into `out`: 10 floats a joint (tx ty tz
/// qx qy qz qw sx sy sz), `len` floats in all. 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live character; `out` is NULL or points to `len` floats.
#[no_mangle]
pub unsafe extern "C" fn tassel_rest_locals(
    c: *const TasselCharacter,
    out: *mut f32,
    len: usize,
) -> i32 {
    guard("tassel_rest_locals", -1, || {
        // SAFETY: the caller's promises.
        let (ch, out) = unsafe { (character(c)?, floats_mut(out, len, "out")?) };
        ch.flat.rest_locals(out).map(|_| 0)
    })
}

/// One frame. `root`: the character's world transform (10 floats); `locals_in`: the
/// animated local transforms, 10 floats a joint in joint order; `locals_out`: the same,
/// with the simulated joints written (every joint: the others copied from `locals_in`);
/// it may be the same buffer as `locals_in` (not otherwise overlapping). `len`: the floats
/// in each (10 a joint). `dt`: seconds since the last frame, ≥ 0 (0 is a valid frame).
/// 0 = ok; -1 = error (NULL, a wrong length, NaN, a rotation that is not a unit
/// quaternion, a negative `dt`): the character and `locals_out` are unchanged.
///
/// # Safety
/// `c` is NULL or a live character; `root` is NULL or 10 floats; `locals_in` and
/// `locals_out` are NULL or `len` floats each.
#[no_mangle]
pub unsafe extern "C" fn tassel_frame(
    c: *mut TasselCharacter,
    root: *const f32,
    locals_in: *const f32,
    locals_out: *mut f32,
    len: usize,
    dt: f32,
) -> i32 {
    guard("tassel_frame", -1, || {
        // SAFETY: the caller's promises; the two buffers are made one slice when they are
        // the same and refused when they overlap otherwise, so no two references alias.
        unsafe {
            let ch = character_mut(c)?;
            let root = floats(root, FLOATS_PER_JOINT, "root")?;
            if std::ptr::eq(locals_in, locals_out) {
                let locals = floats_mut(locals_out, len, "locals_out")?;
                ch.flat.frame(root, locals, dt)?;
            } else {
                let input = floats(locals_in, len, "locals_in")?;
                check_ptr(locals_out, len, "locals_out")?;
                if overlaps(locals_in, len, locals_out, len) {
                    return Err("locals_in and locals_out overlap without being the same \
                                buffer"
                        .into());
                }
                let output = floats_mut(locals_out, len, "locals_out")?;
                ch.flat.frame_into(root, input, output, dt)?;
            }
        }
        Ok(0)
    })
}

/// Every solver starts again from the animated pose on the next frame, whatever its
/// `dt` (NULL: nothing happens, an error is set).
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_reset(c: *mut TasselCharacter) {
    guard("tassel_reset", (), || {
        // SAFETY: the caller's promise.
        unsafe { character_mut(c) }?.flat.reset();
        Ok(())
    })
}

/// The character was moved on purpose (a respawn, a cut): the next frame starts again
/// from the pose at the new place instead of whipping across the world (as
/// `tassel_reset`).
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_teleport(c: *mut TasselCharacter) {
    guard("tassel_teleport", (), || {
        // SAFETY: the caller's promise.
        unsafe { character_mut(c) }?.flat.teleport();
        Ok(())
    })
}

/// Acts on an animation event (a NUL-terminated UTF-8 string) as KawaiiPhysics' anim
/// notifies do: `tassel:reset_dynamics`, `tassel:set_alpha 0.3 [chain]`,
/// `tassel:enable_force NAME`, `tassel:disable_force NAME`, `tassel:force_once NAME` (the
/// forces of the rig file's `[[external_force]]`), `tassel:override NAME stiffness=0.5
/// duration=2 ...` and `tassel:stop_override NAME [blend_out]` (timed settings overrides). Returns 1 when it acted, 0 for an event
/// that does not start with `tassel:` (the game's own), -1 on error (a malformed event, a
/// force or chain that does not exist, NULL; `tassel_last_error` says which).
///
/// # Safety
/// `c` is NULL or a live character; `event` is NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn tassel_event(c: *mut TasselCharacter, event: *const c_char) -> i32 {
    guard("tassel_event", -1, || {
        // SAFETY: the caller's promise.
        let event = unsafe { opt_str(event, "the event") }?.ok_or("the event is NULL")?;
        // SAFETY: the caller's promise.
        let acted = unsafe { character_mut(c) }?.flat.apply_event(event)?;
        Ok(i32::from(acted))
    })
}

/// Starts a timed settings override of the chains (KawaiiPhysics'
/// `StartPhysicsSettingsOverride`): `scales` points to six multipliers, in order damping,
/// stiffness, world damping location, world damping rotation, radius, limit angle (1: no
/// change); they act on the chain named `chain` (NULL: every chain) for `duration`
/// seconds (`INFINITY`: until stopped), blending in over `blend_in` and out over
/// `blend_out`, from the next frame. Up to 8 act at once (a ninth drops the oldest); they
/// multiply. Returns the override's handle (> 0, for `tassel_stop_settings_override`), or
/// -1 on error (a negative or non-finite scale, a duration not > 0, a chain that does not
/// exist, NULL; `tassel_last_error` says which).
///
/// # Safety
/// `c` is NULL or a live character; `scales` is NULL or points to 6 floats; `chain` is
/// NULL or a NUL-terminated string.
#[no_mangle]
pub unsafe extern "C" fn tassel_start_settings_override(
    c: *mut TasselCharacter,
    scales: *const f32,
    duration: f32,
    blend_in: f32,
    blend_out: f32,
    chain: *const c_char,
) -> i32 {
    guard("tassel_start_settings_override", -1, || {
        if scales.is_null() {
            return Err("the scales are NULL".into());
        }
        let mut six = [0.0f32; 6];
        // SAFETY: the caller's promise: 6 floats.
        six.copy_from_slice(unsafe { std::slice::from_raw_parts(scales, 6) });
        // SAFETY: the caller's promise.
        let chain = unsafe { opt_str(chain, "the chain name") }?;
        // SAFETY: the caller's promise.
        let flat = &mut unsafe { character_mut(c) }?.flat;
        let handle = flat.start_settings_override(six, duration, blend_in, blend_out, chain)?;
        Ok(i32::try_from(handle).unwrap_or(i32::MAX))
    })
}

/// Stops a settings override by the handle `tassel_start_settings_override` gave: it
/// blends out from where it is over `blend_out` seconds (0: at once). Returns 1 when an
/// override had the handle, 0 when none did (it ended), -1 for NULL.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_stop_settings_override(
    c: *mut TasselCharacter,
    handle: i32,
    blend_out: f32,
) -> i32 {
    guard("tassel_stop_settings_override", -1, || {
        // SAFETY: the caller's promise.
        let flat = &mut unsafe { character_mut(c) }?.flat;
        let known = u32::try_from(handle).is_ok_and(|h| flat.stop_settings_override(h, blend_out));
        Ok(i32::from(known))
    })
}

/// This character's colliders in the world as its last frame placed them (KawaiiPhysics'
/// shared collision source): every collider (`group` NULL) or those of the rig's
/// `[[collider_group]]` named `group`, 12 floats each into `out` (the shape's kind: 0
/// sphere, 1 capsule, 2 tapered capsule, 3 box, 4 plane; four parameters: sphere radius
/// and inside 0/1, capsule radius and length, tapered capsule radius0, radius1 and length,
/// box half extents; then the world translation x y z and rotation quaternion x y z w).
/// Returns how many colliders there are, writing them only when `capacity` (in colliders)
/// holds them all (ask with `capacity` 0 and `out` NULL); -1 on error (a group the rig does
/// not define, NULL; `tassel_last_error` says which).
///
/// # Safety
/// `c` is NULL or a live character; `group` is NULL or a NUL-terminated string; `out` is
/// NULL (with `capacity` 0) or points to `capacity × 12` floats.
#[no_mangle]
pub unsafe extern "C" fn tassel_shared_colliders(
    c: *const TasselCharacter,
    group: *const c_char,
    out: *mut f32,
    capacity: usize,
) -> i64 {
    guard("tassel_shared_colliders", -1, || {
        // SAFETY: the caller's promise.
        let group = unsafe { opt_str(group, "the group name") }?;
        // SAFETY: the caller's promise.
        let flat = &unsafe { character(c) }?.flat;
        let len = capacity
            .checked_mul(crate::flat::FLOATS_PER_COLLIDER)
            .ok_or("capacity is too large")?;
        let out = if len == 0 {
            &mut [][..]
        } else {
            // SAFETY: the caller's promise: `capacity × 12` floats.
            unsafe { floats_mut(out, len, "out") }?
        };
        Ok(flat.shared_colliders(group, out)? as i64)
    })
}

/// Sets the colliders other characters share with this one (world space, 12 floats each as
/// `tassel_shared_colliders` writes them; `count` 0 clears them): the chains with
/// `use_shared_collision = true` collide with them from the next frame on (set them every
/// frame for colliders that move). Returns 0, or -1 on error (a bad kind, shape or
/// transform, named by index; nothing changes then).
///
/// # Safety
/// `c` is NULL or a live character; `data` is NULL (with `count` 0) or points to
/// `count × 12` floats.
#[no_mangle]
pub unsafe extern "C" fn tassel_set_shared_colliders(
    c: *mut TasselCharacter,
    data: *const f32,
    count: usize,
) -> i32 {
    guard("tassel_set_shared_colliders", -1, || {
        let len = count
            .checked_mul(crate::flat::FLOATS_PER_COLLIDER)
            .ok_or("count is too large")?;
        let data = if len == 0 {
            &[][..]
        } else {
            // SAFETY: the caller's promise: `count × 12` floats.
            unsafe { floats(data, len, "the colliders") }?
        };
        // SAFETY: the caller's promise.
        let flat = &mut unsafe { character_mut(c) }?.flat;
        flat.set_shared_colliders(data)?;
        Ok(0)
    })
}

/// How many joints a solver writes (the others' output is their input). 0 for NULL.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_simulated_joint_count(c: *const TasselCharacter) -> usize {
    guard("tassel_simulated_joint_count", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { character(c) }?.flat.simulated_joints().len())
    })
}

/// The joints a solver writes, ascending, into `out` (`len` entries: exactly
/// `tassel_simulated_joint_count`). 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live character; `out` is NULL or points to `len` entries.
#[no_mangle]
pub unsafe extern "C" fn tassel_simulated_joints(
    c: *const TasselCharacter,
    out: *mut usize,
    len: usize,
) -> i32 {
    guard("tassel_simulated_joints", -1, || {
        // SAFETY: the caller's promises.
        unsafe { copy_indices(character(c)?.flat.simulated_joints(), out, len, "joints") }
    })
}

/// How many joints a frame depends on (`tassel_read_joints`); 0 for NULL.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_read_joint_count(c: *const TasselCharacter) -> usize {
    guard("tassel_read_joint_count", 0, || {
        // SAFETY: the caller's promise.
        Ok(unsafe { character(c) }?.flat.read_joints().len())
    })
}

/// The joints whose animated transforms a frame depends on, ascending, into `out` (`len`
/// entries: exactly `tassel_read_joint_count`). The other joints' entries in
/// `tassel_frame`'s `locals_in` change nothing in the simulated joints: an engine may
/// leave them as they were and skip reading those bones. VRM spring bones without node
/// constraints read their springs, the springs' ancestors and the colliders' nodes;
/// other rigs every joint. 0 = ok, -1 = error.
///
/// # Safety
/// `c` is NULL or a live character; `out` is NULL or points to `len` entries.
#[no_mangle]
pub unsafe extern "C" fn tassel_read_joints(
    c: *const TasselCharacter,
    out: *mut usize,
    len: usize,
) -> i32 {
    guard("tassel_read_joints", -1, || {
        // SAFETY: the caller's promises.
        unsafe { copy_indices(character(c)?.flat.read_joints(), out, len, "read joints") }
    })
}

/// `indices` into `out` (`len` entries, exactly as many).
///
/// # Safety
/// `out` is NULL or points to `len` entries.
unsafe fn copy_indices(
    indices: &[usize],
    out: *mut usize,
    len: usize,
    what: &str,
) -> Result<i32, String> {
    if out.is_null() {
        return Err("out is NULL".into());
    }
    if len != indices.len() {
        return Err(format!(
            "out holds {len} entries; there are {} {what}",
            indices.len()
        ));
    }
    if !(out as usize).is_multiple_of(std::mem::align_of::<usize>()) {
        return Err("out is not aligned".into());
    }
    // SAFETY: non-NULL, aligned, `len` entries by the caller's promise.
    unsafe { std::slice::from_raw_parts_mut(out, len) }.copy_from_slice(indices);
    Ok(0)
}

/// The mode the character steps in ("fixed", "spec", "three-vrm", "classic", "kawaii" or
/// "spcr"),
/// borrowed: valid while the character lives. NULL for NULL.
///
/// # Safety
/// `c` is NULL or a live character.
#[no_mangle]
pub unsafe extern "C" fn tassel_mode(c: *const TasselCharacter) -> *const c_char {
    guard("tassel_mode", std::ptr::null(), || {
        // SAFETY: the caller's promise.
        Ok(unsafe { character(c) }?.mode.as_ptr())
    })
}

/// The message of this thread's last failed call (UTF-8, borrowed until this thread's
/// next failed call), or NULL if none failed.
#[no_mangle]
pub extern "C" fn tassel_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ref().map_or(std::ptr::null(), |c| c.as_ptr()))
}

/// The library's version ("0.1.0"), static.
#[no_mangle]
pub extern "C" fn tassel_version() -> *const c_char {
    const VERSION: &CStr =
        match CStr::from_bytes_with_nul(concat!(env!("CARGO_PKG_VERSION"), "\0").as_bytes()) {
            Ok(v) => v,
            Err(_) => panic!("the version has no NUL inside"),
        };
    VERSION.as_ptr()
}

/// The built-in character as a VRM 1.0 avatar file (GLB bytes: 82 joint nodes, a skinned
/// body, a humanoid, its hair, tail, skirt and charm as 13 VRM springs of 44 joints over 6
/// colliders; made in code, free to redistribute): a character to try without a file of
/// one's own. Returns the file's length in bytes and, when `capacity` is at least that,
/// writes the file to `out`; call with NULL and 0 to learn the length. 0 on an error (see
/// `tassel_last_error`). The same bytes on every call.
///
/// # Safety
/// `out` is NULL or points to `capacity` writable bytes.
#[no_mangle]
pub unsafe extern "C" fn tassel_builtin_avatar(out: *mut u8, capacity: usize) -> usize {
    guard("tassel_builtin_avatar", 0, || {
        let bytes = tassel_gltf::builtin_avatar().map_err(|e| e.to_string())?;
        if capacity >= bytes.len() {
            if out.is_null() {
                return Err("out is NULL".into());
            }
            // SAFETY: non-NULL, `capacity` ≥ len writable bytes by the caller's promise.
            unsafe { std::slice::from_raw_parts_mut(out, bytes.len()) }.copy_from_slice(&bytes);
        }
        Ok(bytes.len())
    })
}

/// `size` bytes of the library's memory, 16-byte aligned (NULL if `size` is 0 or too
/// large): for hosts that cannot hand the library their own memory, such as JavaScript
/// with the WebAssembly module. Free with `tassel_free(p, size)`.
#[no_mangle]
pub extern "C" fn tassel_alloc(size: usize) -> *mut u8 {
    match std::alloc::Layout::from_size_align(size, 16) {
        // SAFETY: the layout's size is not zero.
        Ok(layout) if size > 0 => unsafe { std::alloc::alloc_zeroed(layout) },
        _ => std::ptr::null_mut(),
    }
}

/// Frees what `tassel_alloc(size)` gave (NULL: nothing happens).
///
/// # Safety
/// `p` is NULL or came from `tassel_alloc` with the same `size`, and is not used after.
#[no_mangle]
pub unsafe extern "C" fn tassel_free(p: *mut u8, size: usize) {
    if p.is_null() {
        return;
    }
    if let Ok(layout) = std::alloc::Layout::from_size_align(size, 16) {
        // SAFETY: allocated by `tassel_alloc` with this layout, by the caller's promise.
        unsafe { std::alloc::dealloc(p, layout) }
    }
}
