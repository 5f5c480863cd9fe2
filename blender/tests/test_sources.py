"""The bake reads the armature's evaluated animation, wherever it comes from: the clip in
an NLA strip (no active action) bakes as the same clip as the active action; a bone
constraint's result is keyed (visual keying: with the constraint muted, the baked bone
stands where the constraint put it); a parent object's motion moves the character.

    python test_sources.py ZIP
"""
import math
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(__file__))
import helpers  # noqa: E402

FRAMES = 30
helpers.fresh_blender(sys.argv[-1])
scene = bpy.context.scene
bpy.ops.import_scene.gltf(filepath=os.path.join(helpers.SHARED, "gltf", "Fox.glb"))
fox = helpers.armature()
run = bpy.data.actions["Run"]
fox.tassel.rig_file = os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")
bpy.context.view_layer.objects.active = fox
tail = ["b_Tail02_013", "b_Tail03_014"]
data = fox.animation_data
for track in list(data.nla_tracks):
    data.nla_tracks.remove(track)


def bake_points(names):
    assert bpy.ops.tassel.bake(frame_start=1, frame_end=FRAMES) == {"FINISHED"}
    out = []
    for f in range(1, FRAMES + 1):
        scene.frame_set(f)
        out.append(helpers.world_points(fox, names))
    return out


def gap(a, b, names):
    return max((x[n][k] - y[n][k]).length for x, y in zip(a, b) for n in names for k in (0, 1))


# 1. The active action, then the same clip from an NLA strip with no active action.
data.action = run
from_action = bake_points(tail)
data.action = None
track = data.nla_tracks.new()
track.strips.new("Run", int(run.frame_range[0]), run)
from_nla = bake_points(tail)
d = gap(from_action, from_nla, tail)
if d > 0.01:  # 1e-4 m in the fox's centimetre units
    helpers.fail(f"the clip from an NLA strip bakes {d} units away from the same clip as the action")
if data.action is None or data.action == run:
    helpers.fail("the NLA bake did not assign a new action")
print(f"OK the Run clip from an NLA strip bakes as from the action ({d:.1e} units)")
data.nla_tracks.remove(track)

# 2. A constraint: the hip's rotation limited; its keys hold the constrained pose.
data.action = run
hip = fox.pose.bones["b_Hip_01"]
limit = hip.constraints.new("LIMIT_ROTATION")
limit.use_limit_x = limit.use_limit_y = limit.use_limit_z = True
limit.owner_space = "LOCAL"
constrained = []
for f in range(1, FRAMES + 1):
    scene.frame_set(f)
    constrained.append(fox.matrix_world @ hip.matrix)
free_tail = []
limit.mute = True
for f in range(1, FRAMES + 1):
    scene.frame_set(f)
    free_tail.append((fox.matrix_world @ hip.matrix))
limit.mute = False
moved = max(max(abs(a[i][j] - b[i][j]) for i in range(3) for j in range(3)) for a, b in zip(constrained, free_tail))
if moved < 1e-3:
    helpers.fail("the constraint does not change the hip: the test would show nothing")
bake_points(tail)
limit.mute = True
worst = 0.0
for f, want in zip(range(1, FRAMES + 1), constrained):
    scene.frame_set(f)
    got = fox.matrix_world @ hip.matrix
    worst = max(worst, max(abs(got[i][j] - want[i][j]) for i in range(4) for j in range(4)))
if worst > 1e-3:
    helpers.fail(f"the baked hip is {worst} from where the constraint put it")
print(f"OK a Limit Rotation on the hip is keyed as it evaluated ({worst:.1e}; the constraint moves it {moved:.2f})")
hip.constraints.remove(limit)

# 3. A parent empty carrying the armature: its motion swings the tail.
data.action = run
still = bake_points(tail)
carrier = bpy.data.objects.new("carrier", None)
scene.collection.objects.link(carrier)
fox.parent = carrier
for f in range(1, FRAMES + 1):
    carrier.location = (0.0, 40.0 * math.sin(2 * math.pi * f / 24), 0.0)
    carrier.keyframe_insert("location", frame=f)
data.action = run
carried = bake_points(tail)
# Compare in the carrier's frame: what is left is the tail's own lag.
lag = 0.0
for f, a, b in zip(range(1, FRAMES + 1), still, carried):
    scene.frame_set(f)
    shift = carrier.matrix_world.translation
    lag = max(lag, max(((b[n][1] - shift) - a[n][1]).length for n in tail))
if lag < 0.5:
    helpers.fail(f"a parent's motion moves the tail only {lag} units off the carried clip")
print(f"OK a parent object's motion swings the tail ({lag:.1f} units off the unswung bake)")

# 4. Bones in Euler and axis-angle rotation modes are keyed in their own channels, and the
#    baked motion is the same as in quaternion mode. (The clip keys the tail in
#    quaternions, which a bone in another mode ignores: the tail's channels are left out
#    of the clip for both bakes, so both read the same animation.)
fox.parent = None
untailed = run.copy()
for bag in untailed.layers[0].strips[0].channelbags:
    for fc in [fc for fc in bag.fcurves if any(b in fc.data_path for b in tail)]:
        bag.fcurves.remove(fc)



def unkeyed_tail_at_rest():
    # What a bake left on the unkeyed bones stays on them: put them back at rest.
    for name in tail:
        fox.pose.bones[name].matrix_basis.identity()


data.action = untailed
unkeyed_tail_at_rest()
quaternion_mode = bake_points(tail)
for name, mode in (("b_Tail02_013", "XYZ"), ("b_Tail03_014", "AXIS_ANGLE")):
    fox.pose.bones[name].rotation_mode = mode
data.action = untailed
unkeyed_tail_at_rest()
other_modes = bake_points(tail)
baked = data.action
paths = {fc.data_path for bag in baked.layers[0].strips[0].channelbags for fc in bag.fcurves}
for name, channel in (("b_Tail02_013", "rotation_euler"), ("b_Tail03_014", "rotation_axis_angle")):
    if f'pose.bones["{name}"].{channel}' not in paths:
        helpers.fail(f"{name} is not keyed in {channel}")
d = gap(quaternion_mode, other_modes, tail)
if d > 0.01:
    helpers.fail(f"Euler / axis-angle keys move the tail {d} units from the quaternion keys")
print(f"OK Euler and axis-angle bones keyed in their own channels, the tail as in quaternion mode ({d:.1e} units)")

# 5. A long bake goes in blocks of frames (bake.BLOCK): 600 frames in blocks of 256 key
#    the same bits as one block of all 600, and the same bits twice.
import importlib  # noqa: E402

bake_module = importlib.import_module("bl_ext.user_default.tassel.bake")
for name in tail:
    fox.pose.bones[name].rotation_mode = "QUATERNION"
fox.animation_data.action = run


def keys_of_long_bake():
    # What the last bake's action left on channels the clip does not key stays on the
    # bones: every bake here starts from the rest pose under the clip.
    for bone in fox.pose.bones:
        bone.matrix_basis.identity()
    assert bpy.ops.tassel.bake(frame_start=1, frame_end=600) == {"FINISHED"}
    action = fox.animation_data.action
    values = []
    for bag in action.layers[0].strips[0].channelbags:
        for fc in sorted(bag.fcurves, key=lambda c: (c.data_path, c.array_index)):
            co = [0.0] * (2 * len(fc.keyframe_points))
            fc.keyframe_points.foreach_get("co", co)
            values.append(co)
    fox.animation_data.action = run
    return values


in_blocks = keys_of_long_bake()
again = keys_of_long_bake()
bake_module.BLOCK = 10_000
at_once = keys_of_long_bake()
bake_module.BLOCK = 256
if in_blocks != again:
    diff = [(i, j, a, b) for i, (x, y) in enumerate(zip(in_blocks, again)) for j, (a, b) in enumerate(zip(x, y)) if a != b]
    helpers.fail(f"the same 600-frame bake twice gave different keys: {len(diff)} values, first {diff[:3]}")
if in_blocks != at_once:
    worst = max(abs(a - b) for x, y in zip(in_blocks, at_once) for a, b in zip(x, y))
    helpers.fail(f"600 frames baked in blocks of 256 differ from one block by {worst}")
print(f"OK 600 frames in blocks of 256: the same bits as in one block, and twice "
      f"({sum(len(v) for v in at_once) // 2} keys)")
