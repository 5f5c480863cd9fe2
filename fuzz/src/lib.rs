//! Fuzz target bodies. Each takes arbitrary bytes and panics only when Tassel breaks a
//! promise: a panic inside Tassel itself, a non-finite number in an output pose, a bone
//! farther from the character than its skeleton reaches. An input Tassel refuses with an
//! error is a pass.
//!
//! `fuzz/run.sh TARGET SECONDS` runs one under libFuzzer (coverage-guided, stable Rust);
//! `cargo test -p tassel-fuzz` replays the seed files and every input in
//! `fuzz/regressions/` through the same functions.

use arbitrary::Unstructured;
use glam::{Quat, Vec3};
use std::path::Path;
use std::sync::OnceLock;
use tassel::anim::{Playback, SamplingCursor, SamplingJob, StateMachine};
use tassel::dynamics::cloth::{ClothMode, CollisionSwitches};
use tassel::dynamics::vrm::{
    VrmCollider, VrmColliderGroup, VrmJoint, VrmLimit, VrmLimitShape, VrmMode, VrmOptions,
    VrmShape, VrmSpring, VrmSpringBones, VrmTail,
};
use tassel::dynamics::RigSettings;
use tassel::{builtin, CharacterSim, Skeleton, SkeletonBuilder, Transform};

/// A folder that does not exist: relative buffer URIs in fuzzed files resolve nowhere.
const NO_FOLDER: &str = "/nonexistent/tassel-fuzz";

/// glTF/GLB/VRM bytes → `tassel_gltf::load_slice`; a file that loads is then played: its
/// first clip sampled through its VRM springs for a few frames (spec and fixed mode).
pub fn gltf_import(data: &[u8]) {
    let Ok(model) = tassel_gltf::load_slice(data, Some(Path::new(NO_FOLDER)), "<fuzz>") else {
        return;
    };
    let springs = model
        .vrm
        .as_ref()
        .map(|v| v.springs.clone())
        .unwrap_or_default();
    for mode in [VrmMode::Spec, VrmMode::Fixed] {
        let options = VrmOptions {
            mode,
            ..VrmOptions::default()
        };
        let Ok(mut sim) = CharacterSim::with_vrm(
            model.skeleton.clone(),
            &RigSettings::default(),
            &springs,
            options,
        ) else {
            continue;
        };
        let mut locals = model.skeleton.rest().to_vec();
        let mut cursor = model.clips.first().map(SamplingCursor::new);
        for f in 0..4 {
            let t = f as f32 / 30.0;
            if !sample(model.clips.first(), cursor.as_mut(), t, &mut locals) {
                return;
            }
            let component = Transform::from_translation(Vec3::new(0.3 * t, 0.0, 0.0));
            if sim.frame(&locals, component, 1.0 / 30.0).is_ok() {
                check_pose(&sim, &locals, "gltf_import");
            }
        }
    }
}

/// glTF/GLB/VRM bytes → the C ABI's `tassel_character_load` (as a C, Python or
/// WebAssembly caller uses it: bytes from memory, no rig, `fixed` and `spec`); a character
/// that loads is stepped through `tassel_frame` on a swaying root: every call returns 0 or
/// -1 with a message, every output float is finite, NULL and wrong lengths are refused.
/// The same corpus as [`gltf_import`].
#[allow(unsafe_code)]
pub fn ffi_load(data: &[u8]) {
    use std::ffi::CStr;
    use tassel_ffi::abi::*;
    for mode in [c"fixed", c"spec"] {
        // SAFETY: `data` is `data.len()` bytes; the mode is NUL-terminated.
        let c = unsafe {
            tassel_character_load(data.as_ptr(), data.len(), std::ptr::null(), mode.as_ptr())
        };
        if c.is_null() {
            let e = tassel_last_error();
            assert!(!e.is_null(), "ffi_load: a failed load left no message");
            // SAFETY: a NUL-terminated string of this thread, alive until its next error.
            let message = unsafe { CStr::from_ptr(e) }.to_string_lossy();
            assert!(!message.is_empty(), "ffi_load: an empty message");
            continue;
        }
        // SAFETY: `c` is a live character from a load, freed here.
        unsafe {
            exercise(c, "ffi_load");
            tassel_character_free(c);
        }
    }
}

/// A made character stepped on a swaying root for four frames: every call returns 0 or -1
/// with a message, every output float is finite, a short buffer is refused, no joint past
/// the end has a name; then a crowd of two of it (`what` names the target in messages).
///
/// # Safety
/// `c` is a live character.
#[allow(unsafe_code)]
unsafe fn exercise(c: *mut tassel_ffi::abi::TasselCharacter, what: &str) {
    use tassel_ffi::abi::*;
    // SAFETY: the caller's promise; every buffer is as long as the length given.
    unsafe {
        let n = tassel_joint_count(c);
        let mut locals = vec![0.0f32; n * 10];
        assert_eq!(tassel_rest_locals(c, locals.as_mut_ptr(), locals.len()), 0);
        let mut out = vec![0.0f32; n * 10];
        for f in 0..4 {
            let x = 0.3 * (f as f32 * 0.7).sin();
            let root = [x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
            let ok = tassel_frame(
                c,
                root.as_ptr(),
                locals.as_ptr(),
                out.as_mut_ptr(),
                out.len(),
                1.0 / 30.0,
            );
            if ok == 0 {
                assert!(
                    out.iter().all(|v| v.is_finite()),
                    "{what}: a non-finite output"
                );
            }
            let short = tassel_frame(
                c,
                root.as_ptr(),
                locals.as_ptr(),
                out.as_mut_ptr(),
                out.len().saturating_sub(1),
                1.0 / 30.0,
            );
            assert_eq!(short, -1, "{what}: a short buffer was taken");
        }
        assert!(tassel_joint_name(c, n).is_null());
        ffi_crowd(c, &locals);
    }
}

/// `tassel_character_new` on a skeleton made from the bytes: the first byte is the joint
/// count (0–40), then per joint a parent byte (`b % (n + 2) - 1`: -1, a joint, or one past
/// the end), a name byte (names repeat when bytes do) and ten floats of four bytes each
/// (NaN, infinities and zero rotations included); what is left is the springs JSON (UTF-8,
/// lossy) — or, when it starts with `[`, a rig file. A character that is made is exercised
/// as [`ffi_load`]'s are (frames, a short buffer, a crowd of two).
pub fn ffi_skeleton(data: &[u8]) {
    ffi_skeleton_made(data);
}

/// [`ffi_skeleton`], returning how many of its two modes made a character.
#[allow(unsafe_code)]
pub fn ffi_skeleton_made(data: &[u8]) -> usize {
    use std::ffi::{CStr, CString};
    use tassel_ffi::abi::*;
    let mut made = 0;
    let Some((&count, mut rest_bytes)) = data.split_first() else {
        return made;
    };
    let n = count as usize % 41;
    let mut names = Vec::with_capacity(n);
    let mut parents = Vec::with_capacity(n);
    let mut rest = Vec::with_capacity(n * 10);
    for j in 0..n {
        let take = |bytes: &mut &[u8], k: usize| -> Vec<u8> {
            let (a, b) = bytes.split_at(k.min(bytes.len()));
            *bytes = b;
            a.to_vec()
        };
        let head = take(&mut rest_bytes, 2);
        let parent = head
            .first()
            .map_or(-1, |&b| (b as i32 % (n as i32 + 2)) - 1);
        parents.push(parent);
        names.push(CString::new(format!("j{}", head.get(1).copied().unwrap_or(j as u8))).unwrap());
        for _ in 0..10 {
            let b = take(&mut rest_bytes, 4);
            let v = if b.len() == 4 {
                f32::from_le_bytes([b[0], b[1], b[2], b[3]])
            } else {
                // Short input: the identity's floats.
                [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0][rest.len() % 10]
            };
            rest.push(v);
        }
    }
    let text = String::from_utf8_lossy(rest_bytes).replace('\0', " ");
    let text = CString::new(text).unwrap();
    let (rig, springs) = if rest_bytes.first() == Some(&b'[') {
        (text.as_ptr(), std::ptr::null())
    } else {
        (std::ptr::null(), text.as_ptr())
    };
    let name_ptrs: Vec<*const std::ffi::c_char> = names.iter().map(|s| s.as_ptr()).collect();
    for mode in [c"fixed", c"spec"] {
        // SAFETY: `n` names, parents and 10 n floats; the strings are NUL-terminated.
        let c = unsafe {
            tassel_character_new(
                name_ptrs.as_ptr(),
                parents.as_ptr(),
                rest.as_ptr(),
                n,
                rig,
                springs,
                mode.as_ptr(),
            )
        };
        if c.is_null() {
            let e = tassel_last_error();
            assert!(
                !e.is_null(),
                "ffi_skeleton: a refused skeleton left no message"
            );
            // SAFETY: a NUL-terminated string of this thread, alive until its next error.
            assert!(!unsafe { CStr::from_ptr(e) }.to_bytes().is_empty());
            continue;
        }
        made += 1;
        // SAFETY: `c` is a live character just made, freed here.
        unsafe {
            assert_eq!(tassel_joint_count(c), n);
            exercise(c, "ffi_skeleton");
            tassel_character_free(c);
        }
    }
    made
}

/// A crowd of two characters of `kind` for a few frames (`rest`: the kind's rest locals):
/// every output finite, a short buffer refused.
///
/// # Safety
/// `kind` is a live character; `rest` holds 10 floats a joint.
#[allow(unsafe_code)]
unsafe fn ffi_crowd(kind: *mut tassel_ffi::abi::TasselCharacter, rest: &[f32]) {
    use tassel_ffi::abi::*;
    // SAFETY: the caller's promise; every buffer is as long as the length given.
    unsafe {
        let crowd = tassel_crowd_new(kind);
        assert!(!crowd.is_null(), "ffi_load: no crowd of a loaded character");
        assert_eq!(tassel_crowd_add(crowd), 0);
        assert_eq!(tassel_crowd_add(crowd), 1);
        let mut read = vec![0usize; tassel_crowd_read_joint_count(crowd)];
        assert_eq!(
            tassel_crowd_read_joints(crowd, read.as_mut_ptr(), read.len()),
            0
        );
        let written = tassel_crowd_written_joint_count(crowd);
        let mut locals = Vec::new();
        for _ in 0..2 {
            for &j in &read {
                locals.extend_from_slice(&rest[j * 10..(j + 1) * 10]);
            }
        }
        let mut out = vec![0.0f32; 2 * written * 10];
        for f in 0..3 {
            let x = 0.3 * (f as f32 * 0.9).sin();
            let roots = [x, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0].repeat(2);
            let code = tassel_crowd_frame(
                crowd,
                roots.as_ptr(),
                roots.len(),
                locals.as_ptr(),
                locals.len(),
                out.as_mut_ptr(),
                out.len(),
                1.0 / 30.0,
            );
            assert!(code >= 0, "ffi_load: a crowd frame of good lengths failed");
            if code == 0 {
                assert!(
                    out.iter().all(|v| v.is_finite()),
                    "ffi_load: a non-finite crowd output"
                );
            }
            let short = tassel_crowd_frame(
                crowd,
                roots.as_ptr(),
                roots.len(),
                locals.as_ptr(),
                locals.len().saturating_sub(1),
                out.as_mut_ptr(),
                out.len(),
                1.0 / 30.0,
            );
            assert!(
                short == -1 || locals.is_empty(),
                "ffi_load: a short crowd buffer was taken"
            );
        }
        tassel_crowd_free(crowd);
    }
}

/// Rig TOML text → `RigSettings::from_toml_str`; a rig that parses is compiled on the
/// built-in character and run for a few frames of its walk.
pub fn rig_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(rig) = RigSettings::from_toml_str(text) else {
        return;
    };
    run_rig(&rig, &mut Unstructured::new(&[]), 6);
}

/// State-machine TOML text → `StateMachine::from_toml_str` against the built-in clips;
/// a machine that compiles is updated with changing parameters.
pub fn state_machine_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let c = character();
    let names: Vec<&str> = c.clips.iter().map(|c| c.name.as_str()).collect();
    let durations: Vec<f32> = c.clips.iter().map(|c| c.duration).collect();
    let Ok(machine) = StateMachine::from_toml_str(text, &names, &durations) else {
        return;
    };
    let mut state = machine.new_state();
    let mut plan = Default::default();
    let params = text.len() % 7;
    for f in 0..32 {
        for p in 0..params {
            state.set(p, (f * (p + 1)) as f32 * 0.1);
        }
        machine.update(&mut state, 1.0 / 30.0, &mut plan);
        let total: f32 = plan.layers.iter().map(|l| l.weight).sum();
        assert!(
            total.is_finite() && plan.layers.iter().all(|l| l.time.is_finite()),
            "state machine: non-finite plan {plan:?}"
        );
    }
}

/// Arbitrary settings and motion. The first bytes pick the subject: the built-in
/// character with its rig's numbers, names and switches perturbed (its chains, springs,
/// skirt cloth, rope, or all of them), or a small chain of bones (zero-length ones included) with VRM
/// springs and colliders on top of its bones. Frames then come with hitches (dt from 0 to
/// far beyond a second), teleports, NaN and infinite inputs.
pub fn simulation(data: &[u8]) {
    let mut u = Unstructured::new(data);
    let frames = u.int_in_range(1..=16).unwrap_or(8);
    if u.ratio(1, 3).unwrap_or(false) {
        if let Some((skeleton, springs, options)) = vrm_subject(&mut u) {
            if let Ok(mut sim) =
                CharacterSim::with_vrm(skeleton, &RigSettings::default(), &springs, options)
            {
                drive(&mut sim, &mut u, frames, "simulation (VRM)");
            }
        }
        return;
    }
    // One kind of solver per input keeps an execution short (the cloth alone is most of
    // the character's cost); the colliders stay.
    let full = &character().rig;
    let mut rig = RigSettings {
        colliders: full.colliders.clone(),
        ..RigSettings::default()
    };
    match u.int_in_range(0..=4).unwrap_or(0) {
        0 => {
            rig.chains = full.chains.clone();
            // A third of the chain inputs put points between their bones.
            if u.ratio(1, 3).unwrap_or(false) {
                for c in &mut rig.chains {
                    c.bone_subdivision_count = u.int_in_range(0..=10).unwrap_or(1);
                    c.bone_subdivision_collision_only = u.arbitrary().unwrap_or(true);
                    c.bone_subdivision_densify_by_radius = u.arbitrary().unwrap_or(false);
                }
            }
        }
        1 => rig.springs = full.springs.clone(),
        2 => {
            rig.cloths = full.cloths.clone();
            // Half of the cloth inputs run the spcr mode with its own keys set.
            if u.ratio(1, 2).unwrap_or(false) {
                for c in &mut rig.cloths {
                    c.mode = ClothMode::Spcr;
                    c.collision_lod = Some(u.int_in_range(1..=4).unwrap_or(2));
                    c.collision_sub_iterations = Some(u.int_in_range(1..=10).unwrap_or(1));
                    c.structural_vertical_step_count = Some(u.int_in_range(1..=8).unwrap_or(1));
                    c.limit_from_root = Some(u.arbitrary().unwrap_or(false));
                    c.wind.speed = Some(2.0);
                    c.collision = Some(CollisionSwitches {
                        structural_vertical: true,
                        structural_horizontal: u.arbitrary().unwrap_or(true),
                        shear: u.arbitrary().unwrap_or(true),
                    });
                }
            }
        }
        3 => rig.ropes = full.ropes.clone(),
        _ => rig = full.clone(),
    }
    if perturb_rig(&mut rig, &mut u).is_some() {
        run_rig(&rig, &mut u, frames);
    }
}

/// Samples `clip` (looped) at `t` into `locals`, when there is one; false when the clip
/// cannot be sampled (a bad clip is the loader's business, not a finding here).
fn sample(
    clip: Option<&tassel::anim::Clip>,
    cursor: Option<&mut SamplingCursor>,
    t: f32,
    locals: &mut [Transform],
) -> bool {
    let (Some(clip), Some(cursor)) = (clip, cursor) else {
        return true;
    };
    SamplingJob {
        clip,
        cursor,
        time: t,
        playback: Playback::Loop,
        locals,
    }
    .run()
    .is_ok()
}

fn character() -> &'static builtin::Character {
    static CHARACTER: OnceLock<builtin::Character> = OnceLock::new();
    CHARACTER.get_or_init(builtin::character)
}

fn run_rig(rig: &RigSettings, u: &mut Unstructured, frames: u32) {
    let c = character();
    let Ok(mut sim) = CharacterSim::new(c.skeleton.clone(), rig) else {
        return;
    };
    drive(&mut sim, u, frames, "rig");
}

/// Runs `frames` frames of the walk with motion drawn from `u`; after every frame the
/// simulator accepted, the pose must be finite and within the skeleton's reach.
fn drive(sim: &mut CharacterSim, u: &mut Unstructured, frames: u32, what: &str) {
    let skeleton = sim.skeleton().clone();
    let clip = character()
        .clips
        .get(1)
        .filter(|_| skeleton.len() == character().skeleton.len());
    let mut cursor = clip.map(SamplingCursor::new);
    let mut locals = skeleton.rest().to_vec();
    let mut position = Vec3::ZERO;
    let mut yaw = 0.0f32;
    let mut t = 0.0f32;
    for _ in 0..frames {
        let dt = match u.int_in_range(0..=9).unwrap_or(0) {
            0..=4 => 1.0 / 60.0,
            5 => 0.0,
            6 => unit(u),
            7 => 1.0 / 144.0,
            8 => special(u),
            _ => unit(u) * 30.0,
        };
        if dt.is_finite() && dt > 0.0 {
            t += dt.min(10.0);
        }
        match u.int_in_range(0..=12).unwrap_or(0) {
            0 => position += Vec3::new(1000.0, 0.0, 0.0),
            1 => position = Vec3::splat(special(u)),
            2 => yaw += std::f32::consts::PI * unit(u),
            3 => yaw = special(u),
            _ => position += Vec3::new(0.05, 0.0, 0.02) * (unit(u) - 0.5),
        }
        if !sample(clip, cursor.as_mut(), t, &mut locals) {
            return;
        }
        if u.ratio(1, 8).unwrap_or(false) {
            // A bad animated joint: zero length, NaN or a wild rotation.
            let j = u.choose_index(locals.len()).unwrap_or(0);
            match u.int_in_range(0..=2).unwrap_or(0) {
                0 => locals[j].translation = Vec3::ZERO,
                1 => locals[j].rotation = Quat::from_xyzw(special(u), 0.0, 0.0, 1.0),
                _ => locals[j].translation = Vec3::splat(special(u)),
            }
        }
        let component = Transform::from_translation_rotation(position, Quat::from_rotation_y(yaw));
        if sim.frame(&locals, component, dt).is_ok() {
            check_pose(sim, &locals, what);
        }
        if !position.is_finite() || position.abs().max_element() > 1e5 {
            position = Vec3::ZERO;
        }
        if !yaw.is_finite() {
            yaw = 0.0;
        }
        locals.copy_from_slice(skeleton.rest());
    }
}

/// The pose after an accepted frame: finite, and no joint farther from its root than the
/// animated bone lengths above it add up to (rotations never lengthen a bone), plus, for
/// a joint at or below a spring controller's bone (which moves), twice the largest
/// displacement a spring may reach (its limits are at most 1000 units).
fn check_pose(sim: &CharacterSim, animated: &[Transform], what: &str) {
    let pose = sim.pose();
    let skeleton = sim.skeleton();
    let animated_models = sim.animated_models();
    let mut reach = vec![0.0f32; skeleton.len()];
    for i in 0..sim.springs().len() {
        reach[sim.springs().joint(i)] = 2000.0;
    }
    let mut depth = vec![0usize; skeleton.len()];
    for j in 0..skeleton.len() {
        let l = &pose.locals[j];
        let m = &pose.models[j];
        assert!(
            l.is_finite() && m.is_finite(),
            "{what}: joint '{}' is not finite: local {l:?}, model {m:?} (animated {:?})",
            skeleton.name(j),
            animated[j]
        );
        if let Some(p) = skeleton.parent(j) {
            reach[j] += reach[p]
                + (animated_models[j].translation - animated_models[p].translation).length();
            depth[j] = depth[p] + 1;
            let root = root_of(skeleton, &pose.models, j);
            let from_root = (m.translation - root).length();
            // f32 rounding: at 1e6 units (the coordinate limit) one ulp is 6 cm, and every
            // level of the hierarchy can add one.
            let magnitude = root
                .abs()
                .max_element()
                .max(m.translation.abs().max_element());
            let rounding = 1e-6 * magnitude * (depth[j] + 1) as f32;
            assert!(
                from_root <= reach[j] * 1.001 + 1e-3 + rounding,
                "{what}: joint '{}' is {from_root} from its root, its bones reach {}",
                skeleton.name(j),
                reach[j]
            );
        }
    }
}

fn root_of(skeleton: &Skeleton, models: &[Transform], mut j: usize) -> Vec3 {
    while let Some(p) = skeleton.parent(j) {
        j = p;
    }
    models[j].translation
}

/// A number in 0..1.
fn unit(u: &mut Unstructured) -> f32 {
    u.int_in_range(0..=u16::MAX).unwrap_or(0) as f32 / u16::MAX as f32
}

/// A number a hostile caller might send.
fn special(u: &mut Unstructured) -> f32 {
    *u.choose(&[
        0.0,
        -1.0,
        1e-30,
        1e6,
        -1e6,
        1e20,
        f32::MAX,
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
    ])
    .unwrap_or(&0.0)
}

/// A replacement for a setting whose default is `x`: mostly near it, sometimes extreme.
fn number(u: &mut Unstructured, x: f64) -> f64 {
    match u.int_in_range(0..=7).unwrap_or(0) {
        0..=3 => x * (2.0 * unit(u) as f64),
        4 => x + 10.0 * (unit(u) as f64 - 0.5),
        5 => -x,
        _ => special(u) as f64,
    }
}

/// Changes the rig's numbers, integers, switches and names at random (through its TOML
/// form, so the parser and validation see the result). `None` when the result does not
/// parse or validate — which is the point of many inputs, and a pass.
fn perturb_rig(rig: &mut RigSettings, u: &mut Unstructured) -> Option<()> {
    let mut value = toml::Value::try_from(&*rig).ok()?;
    let rate = u.int_in_range(2..=24).unwrap_or(8);
    perturb_value(&mut value, u, rate);
    let text = toml::to_string(&value).ok()?;
    *rig = RigSettings::from_toml_str(&text).ok()?;
    Some(())
}

fn perturb_value(v: &mut toml::Value, u: &mut Unstructured, rate: u32) {
    let hit = |u: &mut Unstructured| u.ratio(1, rate).unwrap_or(false);
    match v {
        toml::Value::Float(x) => {
            if hit(u) {
                *x = number(u, *x);
            }
        }
        toml::Value::Integer(i) => {
            if hit(u) {
                *i = *u
                    .choose(&[0, 1, 2, 64, 65, 1_000, 100_000, i64::from(u32::MAX)])
                    .unwrap_or(&0);
            }
        }
        toml::Value::Boolean(b) => {
            if hit(u) {
                *b = !*b;
            }
        }
        toml::Value::String(s) => {
            if hit(u) {
                s.push('x');
            }
        }
        toml::Value::Array(a) => {
            for x in a.iter_mut() {
                perturb_value(x, u, rate);
            }
            if hit(u) && !a.is_empty() {
                let i = u.choose_index(a.len()).unwrap_or(0);
                let copy = a[i].clone();
                a.push(copy);
            }
        }
        toml::Value::Table(t) => {
            for (_, x) in t.iter_mut() {
                perturb_value(x, u, rate);
            }
        }
        toml::Value::Datetime(_) => {}
    }
}

/// A chain of 2..=8 bones under a root (some of zero length), one VRM spring over it with
/// drawn parameters, and 0..=4 colliders of every shape on drawn bones.
fn vrm_subject(u: &mut Unstructured) -> Option<(Skeleton, VrmSpringBones, VrmOptions)> {
    let n = u.int_in_range(2..=8).ok()?;
    let mut b = SkeletonBuilder::new();
    let mut parent = b.add("root", None, Transform::IDENTITY);
    for i in 0..n {
        let offset = if u.ratio(1, 6).ok()? {
            Vec3::ZERO
        } else {
            Vec3::new(unit(u) - 0.5, -0.1 - unit(u) * 0.2, unit(u) - 0.5) * 0.3
        };
        parent = b.add(
            format!("b{i}"),
            Some(parent),
            Transform::from_translation(offset),
        );
    }
    let (skeleton, _) = b.build().ok()?;
    let mut springs = VrmSpringBones::default();
    let colliders = u.int_in_range(0..=4).ok()?;
    for _ in 0..colliders {
        let joint = u.int_in_range(0..=n).ok()?;
        let offset = Vec3::new(unit(u) - 0.5, unit(u) - 0.5, unit(u) - 0.5) * 0.2;
        let radius = if u.ratio(1, 8).ok()? {
            special(u)
        } else {
            unit(u) * 0.1
        };
        let inside = u.ratio(1, 4).ok()?;
        let shape = match u.int_in_range(0..=2).ok()? {
            0 => VrmShape::Sphere {
                offset,
                radius,
                inside,
            },
            1 => VrmShape::Capsule {
                offset,
                tail: offset + Vec3::new(0.0, unit(u) * 0.2, 0.0),
                radius,
                inside,
            },
            _ => VrmShape::Plane {
                offset,
                normal: Vec3::new(unit(u) - 0.5, unit(u), unit(u) - 0.5),
            },
        };
        springs.colliders.push(VrmCollider { joint, shape });
    }
    springs.collider_groups.push(VrmColliderGroup {
        name: "all".into(),
        colliders: (0..springs.colliders.len()).collect(),
    });
    let mut joints = Vec::new();
    for j in 1..=n {
        let tail = if j < n {
            VrmTail::Joint(j + 1)
        } else {
            VrmTail::Local(Vec3::new(0.0, -0.07, 0.0))
        };
        let extreme = u.ratio(1, 10).ok()?;
        let limit_kind = u.int_in_range(0..=3u8).ok()?;
        let mut value = |scale: f32| {
            if extreme {
                special(u)
            } else {
                unit(u) * scale
            }
        };
        joints.push(VrmJoint {
            joint: j,
            tail,
            hit_radius: value(0.1),
            stiffness: value(4.0),
            gravity_power: value(2.0),
            gravity_dir: Vec3::NEG_Y,
            drag_force: value(1.0),
            // `VRMC_springBone_limit`: any shape, any angles (bad ones must be refused).
            limit: match limit_kind {
                0 => None,
                1 => Some(VrmLimit::new(VrmLimitShape::Cone { angle: value(4.0) })),
                2 => Some(VrmLimit::new(VrmLimitShape::Hinge { angle: value(4.0) })),
                _ => Some(VrmLimit {
                    shape: VrmLimitShape::Spherical {
                        pitch: value(4.0),
                        yaw: value(2.0),
                    },
                    rotation: Quat::from_xyzw(value(1.0), value(1.0), value(1.0), value(1.0)),
                }),
            },
        });
    }
    springs.springs.push(VrmSpring {
        name: "fuzz".into(),
        joints,
        collider_groups: vec![0],
        center: None,
    });
    let options = VrmOptions {
        mode: if u.ratio(1, 2).ok()? {
            VrmMode::Spec
        } else {
            VrmMode::Fixed
        },
        teleport_distance: if u.ratio(1, 2).ok()? { 0.0 } else { 1.0 },
        ..VrmOptions::default()
    };
    Some((skeleton, springs, options))
}
