"""An armature made a Tassel character: its bones, its rig (TOML and/or the VRM Add-on's
spring bones) and its mode, read from bpy and handed to the native library."""
import os
import tomllib

import numpy as np

from . import native, pose, springs

MODES = {
    "FIXED": "fixed",
    "SPEC": "spec",
    "THREE_VRM": "three-vrm",
    "CLASSIC": "classic",
    "KAWAII": "kawaii",
    "SPCR": "spcr",
}

# The modes as Blender's enum items (identifier, name, description), shared by the panel's
# setting and the operator.
MODE_ITEMS = [
    ("FIXED", "Fixed", "Fixed internal steps: the look does not depend on the frame rate"),
    ("SPEC", "Spec", "VRM springs as the VRM specification steps them, once a frame"),
    ("THREE_VRM", "three-vrm", "VRM springs as three-vrm 3.5.5 runs them"),
    ("CLASSIC", "Classic", "Chains frame by frame, as KawaiiPhysics 1.10"),
    ("KAWAII", "KawaiiPhysics 1.21", "Chains as KawaiiPhysics 1.21's fixed substepping runs them"),
    ("SPCR", "SPCR", "Bone cloths as SPCRJointDynamicsUE4's update runs them"),
]
DEFAULT_STEP_RATE = 60.0


class RigError(ValueError):
    """The armature, its rig or the request cannot make a character; the message says why."""


def skeleton_of(armature):
    """The armature object's bones as a pose.Skeleton (armature space, the bones' order)."""
    bones = armature.data.bones
    index = {b.name: i for i, b in enumerate(bones)}
    parents = [index[b.parent.name] if b.parent else -1 for b in bones]
    rest = np.array([np.array(b.matrix_local) for b in bones]).reshape(-1, 4, 4)
    return pose.Skeleton([b.name for b in bones], parents, rest)


def rig_text(settings):
    """The rig's TOML text from the armature's settings (a text block wins over a file),
    or None."""
    if settings.rig_text is not None:
        return settings.rig_text.as_string()
    path = settings.rig_file.strip()
    if not path:
        return None
    import bpy

    full = bpy.path.abspath(path)
    if not os.path.isfile(full):
        raise RigError(f"the rig file {full} does not exist")
    try:
        with open(full, encoding="utf-8") as f:
            return f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise RigError(f"the rig file {full} cannot be read as UTF-8 text: {e}") from None


def with_step_rate(toml_text, step_rate):
    """The rig text with the fixed mode's VRM step rate set (a `[vrm]` table), checked:
    broken TOML and a rig whose own `[vrm]` step rate differs are refused."""
    try:
        parsed = tomllib.loads(toml_text or "")
    except tomllib.TOMLDecodeError as e:
        raise RigError(f"the rig is not valid TOML: {e}") from None
    if "vrm" in parsed:
        table = parsed["vrm"]
        own = table.get("step_rate", DEFAULT_STEP_RATE) if isinstance(table, dict) else None
        if not isinstance(own, (int, float)) or isinstance(own, bool):
            raise RigError(f"the rig's vrm must be a table with a number step_rate, not {table!r}")
        if float(own) != float(step_rate):
            raise RigError(f"the rig's [vrm] table sets step_rate {float(own)}, the bake asks for {float(step_rate)}")
        return toml_text
    if float(step_rate) == DEFAULT_STEP_RATE and toml_text is None:
        return None
    return (toml_text or "") + f"\n[vrm]\nstep_rate = {float(step_rate)!r}\n"


def make(armature, mode="FIXED", step_rate=DEFAULT_STEP_RATE):
    """(Character, Skeleton) for an armature object from its `tassel` settings. Raises
    RigError (bad settings) or native.TasselError (Tassel refused the rig: it names the
    bone or key)."""
    if armature is None or armature.type != "ARMATURE":
        what = "nothing" if armature is None else f"'{armature.name}' ({armature.type.lower()})"
        raise RigError(f"select an armature: the active object is {what}")
    if mode not in MODES:
        raise RigError(f"mode {mode} is not one of {', '.join(MODES)}")
    settings = armature.tassel
    skeleton = skeleton_of(armature)
    text = rig_text(settings)
    vrm = None
    if settings.use_vrm_springs:
        try:
            vrm = springs.springs_json(armature, {n: i for i, n in enumerate(skeleton.names)})
        except ValueError as e:
            raise RigError(str(e)) from None
    if text is None and vrm is None:
        raise RigError(
            f"'{armature.name}' has no rig: set a rig file or text block, or import a VRM "
            "with spring bones (the VRM Add-on for Blender)"
        )
    text = with_step_rate(text, step_rate)
    character = native.Character(skeleton.names, skeleton.parents, skeleton.rest, text, vrm, MODES[mode])
    return character, skeleton


def read_pose(evaluated, order, buffer, which="matrix"):
    """The evaluated armature's pose matrices (`which`: "matrix", armature space, or
    "matrix_basis") in the skeleton's bone order: `order[i]` is bone i's index among
    `pose.bones`; `buffer` is scratch (n × 16 float32)."""
    evaluated.pose.bones.foreach_get(which, buffer.reshape(-1))
    # bpy lays matrices out column by column.
    return buffer.reshape(-1, 4, 4).transpose(0, 2, 1)[order].astype(np.float64)


def pose_order(armature, skeleton):
    """For each skeleton bone, its index among the armature's pose bones."""
    bones = armature.pose.bones
    return np.array([bones.find(name) for name in skeleton.names], dtype=np.intp)
