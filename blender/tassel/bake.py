"""Baking: the armature's evaluated animation played through Tassel, every bone keyed on
every frame into a new action (`bpy.ops.tassel.bake`), and the stepper the live preview
shares."""
import time

import bpy
import numpy as np

from . import character, pose

# True while a bake plays the frames: the live preview's handlers stand aside.
BAKING = [False]

# Keyframe.interpolation's enum value for LINEAR.
_LINEAR = bpy.types.Keyframe.bl_rna.properties["interpolation"].enum_items["LINEAR"].value


class Stepper:
    """One armature stepped frame by frame: reads its evaluated pose and object
    transform, runs Tassel, returns every bone's local transform (n × 10)."""

    def __init__(self, armature, mode, step_rate):
        self.character, self.skeleton = character.make(armature, mode, step_rate)
        n = len(self.skeleton.names)
        self.order = character.pose_order(armature, self.skeleton)
        self.buffer = np.empty((n, 16), dtype=np.float32)
        self.locals_in = np.empty((n, 10), dtype=np.float32)
        self.locals_out = np.empty((n, 10), dtype=np.float32)

    def step(self, depsgraph, armature, dt):
        """One frame on the armature as `depsgraph` evaluates it; dt = 0 after a reset places."""
        evaluated = armature.evaluated_get(depsgraph)
        matrices = character.read_pose(evaluated, self.order, self.buffer)
        bases = character.read_pose(evaluated, self.order, self.buffer, "matrix_basis")
        self.locals_in[:] = self.skeleton.pose_locals(matrices, bases)
        root = pose.root_transform(np.array(evaluated.matrix_world))
        self.character.frame(root, self.locals_in, self.locals_out, dt)
        return self.locals_out


# The most bone-frames one bake keys (frames × bones), as `tassel bake`'s limit per clip:
# every bone is keyed on every frame, ten channels each.
MAX_BAKE_KEYS = 1 << 23
# Frames read, converted and stepped together (bounds the scratch memory of a long bake).
BLOCK = 256


def simulate(context, armature, mode, frame_start, frame_end, step_rate, report_progress=None):
    """Plays frames frame_start..frame_end (the first places the solvers, each later one
    steps 1/fps) and returns (skeleton, simulated joints, locals: frames × n × 10). Changes
    nothing but the scene's current frame, which it puts back.

    The animation does not depend on the simulation, so the evaluated poses of a block of
    frames are read first (Blender's evaluation, frame by frame), turned into local
    transforms in one batch, then stepped through Tassel: numpy's cost per call is paid
    once a block, not once a frame."""
    scene = context.scene
    stepper = Stepper(armature, mode, step_rate)
    skeleton = stepper.skeleton
    n = len(skeleton.names)
    frames = frame_end - frame_start + 1
    if frames * n > MAX_BAKE_KEYS:
        raise character.RigError(
            f"frames {frame_start}–{frame_end} × {n} bones is more than the limit of "
            f"{MAX_BAKE_KEYS} bone-frames per bake; bake a shorter range"
        )
    dt = scene.render.fps_base / scene.render.fps
    block = min(BLOCK, frames)
    matrices = np.empty((block, n, 4, 4))
    bases = np.empty((block, n, 4, 4))
    worlds = np.empty((block, 4, 4))
    out = np.empty((frames, n, 10), dtype=np.float32)
    current = scene.frame_current
    # The character was made at the rest pose at the origin of glTF's axes: the first
    # frame places every solver on this pose and place instead of swinging from there.
    stepper.character.reset()
    BAKING[0] = True
    try:
        for start in range(0, frames, block):
            count = min(block, frames - start)
            for k in range(count):
                scene.frame_set(frame_start + start + k)
                evaluated = armature.evaluated_get(context.evaluated_depsgraph_get())
                matrices[k] = character.read_pose(evaluated, stepper.order, stepper.buffer)
                bases[k] = character.read_pose(evaluated, stepper.order, stepper.buffer, "matrix_basis")
                worlds[k] = np.array(evaluated.matrix_world)
                if report_progress:
                    report_progress(start + k + 1, frames)
            animated = skeleton.pose_locals(matrices[:count], bases[:count]).astype(np.float32)
            roots = pose.transforms_from_matrices(pose.TO_TASSEL[None] @ worlds[:count])
            for k in range(count):
                f = start + k
                try:
                    stepper.character.frame(roots[k], animated[k], out[f], 0.0 if f == 0 else dt)
                except character.native.TasselError as e:
                    raise character.native.TasselError(f"frame {frame_start + f}: {e}") from None
    finally:
        BAKING[0] = False
        scene.frame_set(current)
    return skeleton, stepper.character.simulated, out


def keys_of(skeleton, locals_):
    """Pose-bone keys for locals (frames × n × 10): location (f × n × 3), rotation as
    quaternions w x y z without sign flips between frames (f × n × 4), scale (f × n × 3)."""
    frames, n, _ = locals_.shape
    bases = skeleton.rest_local_inverses[None] @ pose.matrices_from_transforms(
        locals_.reshape(-1, 10).astype(np.float64)).reshape(frames, n, 4, 4)
    trs = pose.transforms_from_matrices(bases.reshape(-1, 4, 4)).reshape(frames, n, 10)
    q = trs[..., [6, 3, 4, 5]]
    # The shortest way from each key to the next: flip a key opposite its predecessor.
    flips = np.ones((frames, n))
    flips[1:] = np.where(np.einsum("fnk,fnk->fn", q[1:], q[:-1]) < 0, -1.0, 1.0)
    q *= np.cumprod(flips, axis=0)[..., None]
    return trs[..., 0:3], q, trs[..., 7:10]


def _new_action(armature, source, name):
    """A new action for the bake: the source's other channels (the object's own motion,
    custom properties) kept, its bone channels dropped; assigned to the armature."""
    if source is not None:
        action = source.copy()
        action.name = name
        for layer in action.layers:
            for strip in layer.strips:
                for bag in strip.channelbags:
                    for fc in [fc for fc in bag.fcurves if fc.data_path.startswith("pose.bones[")]:
                        bag.fcurves.remove(fc)
    else:
        action = bpy.data.actions.new(name)
    data = armature.animation_data or armature.animation_data_create()
    data.action = action
    if data.action_slot is None and len(action.slots):
        data.action_slot = action.slots[0]
    return action


def _key(action, armature, path, index, group, frames, values):
    fc = action.fcurve_ensure_for_datablock(armature, path, index=index, group_name=group)
    points = fc.keyframe_points
    points.clear()
    points.add(len(frames))
    co = np.empty(2 * len(frames), dtype=np.float32)
    co[0::2] = frames
    co[1::2] = values
    points.foreach_set("co", co)
    points.foreach_set("interpolation", [_LINEAR] * len(frames))
    fc.update()


def write_action(armature, skeleton, frame_start, locals_):
    """Keys every bone of `skeleton` on every frame from locals (frames × n × 10) into a
    new action assigned to the armature; the source action keeps a fake user. Returns it."""
    from mathutils import Quaternion

    loc, quat, scale = keys_of(skeleton, locals_)
    data = armature.animation_data
    source = data.action if data else None
    if source is not None:
        source.use_fake_user = True
    name = f"{source.name if source else armature.name}.tassel"
    action = _new_action(armature, source, name)
    frames = np.arange(frame_start, frame_start + len(locals_), dtype=np.float32)
    for i, bone in enumerate(skeleton.names):
        pb = armature.pose.bones[bone]
        prefix = f'pose.bones["{bpy.utils.escape_identifier(bone)}"].'
        for c in range(3):
            _key(action, armature, prefix + "location", c, bone, frames, loc[:, i, c])
            _key(action, armature, prefix + "scale", c, bone, frames, scale[:, i, c])
        mode = pb.rotation_mode
        if mode == "QUATERNION":
            channels, values = "rotation_quaternion", quat[:, i, :]
        elif mode == "AXIS_ANGLE":
            axis_angles = []
            for q in quat[:, i, :]:
                axis, angle = Quaternion(q).to_axis_angle()
                axis_angles.append((angle, axis.x, axis.y, axis.z))
            channels, values = "rotation_axis_angle", np.array(axis_angles)
        else:
            eulers, last = [], None
            for q in quat[:, i, :]:
                e = Quaternion(q).to_euler(mode, last) if last is not None else Quaternion(q).to_euler(mode)
                eulers.append(tuple(e))
                last = e
            channels, values = "rotation_euler", np.array(eulers)
        for c in range(values.shape[1]):
            _key(action, armature, prefix + channels, c, bone, frames, values[:, c])
    return action


class Progress:
    """The window manager's progress (0–100 %), and a line on the console each 10 % when
    headless. Called with (frames done, frames)."""

    def __init__(self, context, label):
        self.wm = context.window_manager
        self.label = label
        self.headless = bpy.app.background
        self.started = time.perf_counter()
        self.next_line = 0
        self.wm.progress_begin(0, 100)

    def __call__(self, done, total):
        percent = 100 * done // max(total, 1)
        self.wm.progress_update(percent)
        if self.headless and percent >= self.next_line:
            print(f"Tassel: baking {self.label}: {percent} %", flush=True)
            self.next_line = percent // 10 * 10 + 10

    def end(self):
        self.wm.progress_end()


class TASSEL_OT_bake(bpy.types.Operator):
    """Bake the armature's secondary motion into a new action (every bone, every frame)"""

    bl_idname = "tassel.bake"
    bl_label = "Bake Secondary Motion"
    bl_options = {"REGISTER", "UNDO"}

    mode: bpy.props.EnumProperty(name="Mode", items=character.MODE_ITEMS, default="FIXED")
    frame_start: bpy.props.IntProperty(name="Start", description="First frame (places the solvers)")
    frame_end: bpy.props.IntProperty(name="End", description="Last frame")
    step_rate: bpy.props.FloatProperty(
        name="Step Rate", description="Fixed mode: VRM spring steps per second", default=60.0,
        min=10.0, max=1000.0,
    )

    @classmethod
    def poll(cls, context):
        return context.mode in {"OBJECT", "POSE"}

    def _settings(self, context, armature):
        """The operator's values, or the armature's panel settings for those not given."""
        settings = getattr(armature, "tassel", None)
        scene = context.scene
        given = self.properties.is_property_set
        mode = self.mode if given("mode") or settings is None else settings.mode
        step_rate = self.step_rate if given("step_rate") or settings is None else settings.step_rate
        use_scene = settings is None or settings.use_scene_range
        start = self.frame_start if given("frame_start") else (scene.frame_start if use_scene else settings.frame_start)
        end = self.frame_end if given("frame_end") else (scene.frame_end if use_scene else settings.frame_end)
        return mode, step_rate, start, end

    def execute(self, context):
        armature = context.active_object
        if armature is None or armature.type != "ARMATURE":
            what = "nothing is active" if armature is None else f"'{armature.name}' is a {armature.type.lower()}"
            self.report({"ERROR"}, f"Tassel bakes an armature: {what}")
            return {"CANCELLED"}
        mode, step_rate, start, end = self._settings(context, armature)
        if end < start:
            self.report({"ERROR"}, f"the frame range {start}–{end} is empty: the end is before the start")
            return {"CANCELLED"}
        progress = Progress(context, f"'{armature.name}' frames {start}–{end}")
        try:
            skeleton, simulated, locals_ = simulate(context, armature, mode, start, end, step_rate, progress)
        except (character.RigError, character.native.TasselError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        finally:
            progress.end()
        action = write_action(armature, skeleton, start, locals_)
        seconds = time.perf_counter() - progress.started
        self.report(
            {"INFO"},
            f"Tassel baked frames {start}–{end} of '{armature.name}' ({len(simulated)} simulated bones, "
            f"{mode.lower()}) into '{action.name}' in {seconds:.2f} s",
        )
        return {"FINISHED"}
