"""Bad input writes nothing: a rig naming a missing bone, broken TOML, a selection that is
not an armature, an empty range, no rig at all and a step rate the rig contradicts each
get an error naming the problem; no action is written and nothing else changes.

    python test_bad_input.py ZIP
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(__file__))
import helpers  # noqa: E402

helpers.fresh_blender(sys.argv[-1])
scene = bpy.context.scene
bpy.ops.import_scene.gltf(filepath=os.path.join(helpers.SHARED, "gltf", "Fox.glb"))
fox = helpers.armature()
run = fox.animation_data.action = bpy.data.actions["Run"]
mesh = [o for o in scene.objects if o.type == "MESH"][0]
good = open(os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")).read()
text = bpy.data.texts.new("rig.toml")


def state():
    """Everything a failed bake must leave as it was."""
    return (
        sorted(bpy.data.actions.keys()),
        fox.animation_data.action.name,
        run.use_fake_user,
        scene.frame_current,
        [tuple(b.matrix_basis.col[3]) + tuple(b.rotation_quaternion) for b in fox.pose.bones],
        sum(len(fc.keyframe_points) for bag in run.layers[0].strips[0].channelbags for fc in bag.fcurves),
    )


def refused(label, expected, active=fox, **kwargs):
    bpy.context.view_layer.objects.active = active
    before = state()
    try:
        result = bpy.ops.tassel.bake(**kwargs)
    except RuntimeError as e:
        message = str(e)
    else:
        helpers.fail(f"{label}: the bake was not refused ({result})")
    if expected not in message:
        helpers.fail(f"{label}: the error does not say '{expected}': {message!r}")
    if state() != before:
        helpers.fail(f"{label}: something changed although the bake was refused")
    print(f"OK {label}: {message.strip()}")


scene.frame_set(7)
text.from_string(good.replace('root = "b_Tail01_012"', 'root = "b_Tail09_999"'))
fox.tassel.rig_text = text
refused("a rig naming a missing bone", "b_Tail09_999", frame_start=1, frame_end=40)
text.from_string("[[chain]\nname = ")
refused("broken TOML", "not valid TOML", frame_start=1, frame_end=40)
text.from_string(good.replace("radius = 3.0", "radius = -3.0"))
refused("a negative radius", "radius", frame_start=1, frame_end=40)
text.from_string(good)
refused("a mesh selected", "'fox' is a mesh", active=mesh, frame_start=1, frame_end=40)
refused("nothing selected", "nothing is active", active=None, frame_start=1, frame_end=40)
refused("an empty range", "is empty", frame_start=40, frame_end=39)
refused("a range too long to key", "bone-frames", frame_start=1, frame_end=10_000_000)
text.from_string(good + "\n[vrm]\nstep_rate = \"fast\"\n")
refused("a step rate that is not a number", "number step_rate", frame_start=1, frame_end=40)
text.from_string(good + "\n[vrm]\nstep_rate = 90\n")
refused("a step rate the rig contradicts", "step_rate 90", frame_start=1, frame_end=40, step_rate=60)
text.from_string(good)
fox.tassel.rig_text = None
refused("no rig", "has no rig", frame_start=1, frame_end=40)
fox.tassel.rig_file = "/nonexistent/fox.toml"
refused("a rig file that does not exist", "/nonexistent/fox.toml", frame_start=1, frame_end=40)
import tempfile  # noqa: E402

binary = os.path.join(tempfile.mkdtemp(), "rig.toml")
with open(binary, "wb") as f:
    f.write(b"[[chain]]\nname = \"\xff\xfe\"\n")
fox.tassel.rig_file = binary
refused("a rig file that is not UTF-8", "UTF-8", frame_start=1, frame_end=40)
# Not bad input: a bone scaled to nothing (how animators hide parts) bakes; its subtree
# sits collapsed on its head, every key finite.
text.from_string(good)
fox.tassel.rig_file = ""
fox.tassel.rig_text = text
hidden = run.copy()
fox.animation_data.action = hidden
hip = fox.pose.bones["b_Hip_01"]
for frame, s in ((4, 1.0), (5, 0.0), (6, 0.0), (7, 1.0)):
    hip.scale = (s, s, s)
    hip.keyframe_insert("scale", frame=frame)
scene.frame_set(1)
assert bpy.ops.tassel.bake(frame_start=1, frame_end=10) == {"FINISHED"}
import math  # noqa: E402
keys = [k.co[1] for bag in fox.animation_data.action.layers[0].strips[0].channelbags
        for fc in bag.fcurves for k in fc.keyframe_points]
if not all(math.isfinite(v) for v in keys):
    helpers.fail("a bake through a bone scaled to nothing wrote a key that is not finite")
scene.frame_set(5)
head = fox.matrix_world @ hip.head
tip = fox.matrix_world @ fox.pose.bones["b_Tail03_014"].tail
if (tip - head).length > 1e-3:
    helpers.fail(f"under a hip scaled to nothing the tail's tip is {(tip - head).length} from the hip")
scene.frame_set(9)
print(f"OK a hip scaled to nothing on frames 5–6 bakes: {len(keys)} finite keys, the tail collapsed on it")
fox.animation_data.action = run
# And the good rig still bakes after all that.
fox.tassel.rig_file = ""
fox.tassel.rig_text = text
scene.frame_set(7)
bpy.context.view_layer.objects.active = fox
assert bpy.ops.tassel.bake(frame_start=1, frame_end=40) == {"FINISHED"}
assert fox.animation_data.action.name == "Run.tassel" and run.use_fake_user
print("OK the same armature bakes once the rig is good")
