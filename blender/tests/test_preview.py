"""The live preview: frame after frame it poses the simulated bones as the bake keys them;
back at the range's start it resets; any other jump teleports (the solvers start again
from the pose there, as a bake that starts on that frame).

    python test_preview.py ZIP
"""
import os
import sys

import bpy

sys.path.insert(0, os.path.dirname(__file__))
import helpers  # noqa: E402

TOLERANCE = 1e-3  # the fox's units (centimetres): 1e-5 m
helpers.fresh_blender(sys.argv[-1])
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 30
bpy.ops.import_scene.gltf(filepath=os.path.join(helpers.SHARED, "gltf", "Fox.glb"))
fox = helpers.armature()
run = fox.animation_data.action = bpy.data.actions["Run"]
fox.tassel.rig_file = os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")
bpy.context.view_layer.objects.active = fox
bones = ["b_Tail02_013", "b_Tail03_014"]


def points_of_bake(start, end):
    fox.animation_data.action = run
    assert bpy.ops.tassel.bake(frame_start=start, frame_end=end) == {"FINISHED"}
    out = {}
    for f in range(start, end + 1):
        scene.frame_set(f)
        out[f] = helpers.world_points(fox, bones)
    fox.animation_data.action = run
    return out


def preview_at(frame):
    scene.frame_set(frame)
    bpy.context.view_layer.update()
    return helpers.world_points(fox, bones)


def gap(a, b):
    return max((a[n][k] - b[n][k]).length for n in bones for k in (0, 1))


baked = points_of_bake(1, 30)
from_20 = points_of_bake(20, 21)
scene.frame_set(1)
fox.tassel.preview = True
worst = max(gap(preview_at(f), baked[f]) for f in range(1, 31))
if worst > TOLERANCE:
    helpers.fail(f"playback differs from the bake by {worst}")
print(f"OK playing frames 1–30 poses the tail as the bake, within {worst:.1e}")
preview_at(12)
again = gap(preview_at(1), baked[1])
if again > TOLERANCE:
    helpers.fail(f"back at the start the preview did not reset: {again}")
print(f"OK back at the start it resets ({again:.1e} from the bake's frame 1)")
jump = gap(preview_at(20), from_20[20])
if jump > TOLERANCE:
    helpers.fail(f"a jump to frame 20 did not start again from the pose there: {jump}")
swing = gap(preview_at(20), baked[20])
print(f"OK a jump teleports: frame 20 as a bake starting there ({jump:.1e}); "
      f"the tail is {swing:.1f} units from where playing through put it")
fox.tassel.preview = False
scene.frame_set(5)
bpy.context.view_layer.update()
if gap(helpers.world_points(fox, bones), baked[5]) < TOLERANCE:
    helpers.fail("with the preview off, the tail still follows the simulation")
print("OK with the preview off the animation plays as it is")
# Bones the action does not key keep what the preview wrote only while it runs.
untailed = run.copy()
for bag in untailed.layers[0].strips[0].channelbags:
    for fc in [fc for fc in bag.fcurves if any(b in fc.data_path for b in bones)]:
        bag.fcurves.remove(fc)
fox.animation_data.action = untailed
for b in bones:
    fox.pose.bones[b].matrix_basis.identity()
own = {b: fox.pose.bones[b].matrix_basis.copy() for b in bones}
fox.tassel.preview = True
for f in range(1, 11):
    preview_at(f)
moved = max((fox.pose.bones[b].matrix_basis.to_quaternion().rotation_difference(own[b].to_quaternion())).angle for b in bones)
fox.tassel.preview = False
back = max((fox.pose.bones[b].matrix_basis.to_quaternion().rotation_difference(own[b].to_quaternion())).angle for b in bones)
if moved < 1e-3 or back > 1e-6:
    helpers.fail(f"unkeyed tail: turned {moved} rad while previewing, {back} rad after switching it off")
print(f"OK an unkeyed tail turns {moved:.2f} rad while previewing and gets its own pose back after")
# A bake while the preview is on reads the animation, not what the preview last wrote on
# the unkeyed tail: the same keys as a bake with the preview off.
fox.animation_data.action = untailed
for b in bones:
    fox.pose.bones[b].matrix_basis.identity()
assert bpy.ops.tassel.bake(frame_start=1, frame_end=20) == {"FINISHED"}
scene.frame_set(20)
quiet = helpers.world_points(fox, bones)
fox.animation_data.action = untailed
for b in bones:
    fox.pose.bones[b].matrix_basis.identity()
fox.tassel.preview = True
for f in range(1, 11):
    preview_at(f)
assert bpy.ops.tassel.bake(frame_start=1, frame_end=20) == {"FINISHED"}
fox.tassel.preview = False
scene.frame_set(20)
during = helpers.world_points(fox, bones)
if gap(quiet, during) > 1e-3:
    helpers.fail(f"a bake with the preview on differs by {gap(quiet, during)} from one with it off")
print(f"OK a bake with the preview on reads the animation ({gap(quiet, during):.1e} from one with it off)")
