"""VRM 0.x secondary animation, as the VRM Add-on for Blender holds it (a bone group whose
root bone's whole subtree swings; a collider group of spheres as empties parented to a
bone): an armature given VRM 0.x springs and a collider in the add-on's properties, baked,
equals `tassel simulate` of the VRM 0.x file the add-on's own exporter writes from it.

    python test_vrm0.py ZIP

The add-on exports VRM 0.x facing -Z (turned half a turn about +Y from Blender's import),
so the file's (x, y, z) is Blender's (-x, z, y), and the sway along the file's +x is a sway
along Blender's -x.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

import bpy
from mathutils import Matrix

sys.path.insert(0, os.path.dirname(__file__))
import helpers  # noqa: E402

FRAMES, FPS, AMP = 60, 60, 0.3
TOLERANCE = 1e-4

helpers.fresh_blender(sys.argv[-1], vrm_addon=True)
scene = bpy.context.scene
scene.render.fps = FPS
assert bpy.ops.import_scene.vrm(filepath=os.path.join(helpers.SHARED, "vrm", "smoke_spring.vrm")) == {"FINISHED"}
arm = helpers.armature()
bpy.context.view_layer.objects.active = arm
ext = arm.data.vrm_addon_extension
ext.spec_version = "0.0"
secondary = ext.vrm0.secondary_animation
name = arm.name
assert bpy.ops.vrm.add_vrm0_secondary_animation_collider_group(armature_object_name=name) == {"FINISHED"}
group = secondary.collider_groups[0]
group.node.bone_name = "head"
assert bpy.ops.vrm.add_vrm0_secondary_animation_collider_group_collider(
    armature_object_name=name, collider_group_index=0, bone_name="head") == {"FINISHED"}
empty = group.colliders[0].bpy_object
# A 4 cm sphere beside the hanging chain, where the sway throws it.
empty.matrix_world = Matrix.Translation((-0.07, 0.0, 1.22))
empty.empty_display_size = 0.04
assert bpy.ops.vrm.add_vrm0_secondary_animation_group(armature_object_name=name) == {"FINISHED"}
bones = secondary.bone_groups[0]
bones.bones.add().bone_name = "spring_joint_0"
bones.stiffiness, bones.gravity_power, bones.drag_force, bones.hit_radius = 0.5, 0.5, 0.5, 0.02
bones.gravity_dir = (0.0, 0.0, -1.0)
assert bpy.ops.vrm.add_vrm0_secondary_animation_group_collider_group(
    armature_object_name=name, bone_group_index=0) == {"FINISHED"}
bones.collider_groups[0].collider_group_uuid = group.uuid
ext.spring_bone1.springs.clear()

folder = tempfile.mkdtemp()
exported = os.path.join(folder, "vrm0.vrm")
assert bpy.ops.export_scene.vrm(filepath=exported) == {"FINISHED"}
doc = helpers.gltf_json(exported)
if "VRM" not in doc.get("extensions", {}):
    helpers.fail("the add-on did not write a VRM 0.x file")
out = os.path.join(folder, "sim.json")
subprocess.run([helpers.TASSEL, "simulate", exported, "--mode", "fixed", "--frames", str(FRAMES),
                "--dt", repr(1.0 / FPS), "--motion", "sin", "--amp", str(AMP), "--axis", "x",
                "--out", out], check=True, stdout=subprocess.DEVNULL)
ref = json.load(open(out))
for f in range(FRAMES + 1):
    arm.location.x = -AMP * math.sin(2 * math.pi * f / FPS)
    arm.keyframe_insert("location", index=0, frame=1 + f)
assert bpy.ops.tassel.bake(mode="FIXED", frame_start=1, frame_end=1 + FRAMES) == {"FINISHED"}
worst, touched = 0.0, 0.0
centre = None
for sample in ref["samples"]:
    scene.frame_set(1 + sample["frame"])
    for j, want in zip(ref["joints"], sample["world_pos"]):
        got = arm.matrix_world @ arm.pose.bones[j["name"]].head
        worst = max(worst, math.dist((-got.x, got.z, got.y), want))
if len(ref["joints"]) != 4:
    helpers.fail(f"the bone group should swing 4 joints, tassel simulate has {len(ref['joints'])}")
if worst > TOLERANCE:
    helpers.fail(f"VRM 0.x: {worst:.2e} m from tassel simulate of the add-on's export")
# Without the collider the chain goes elsewhere: the collider was read and it mattered.
bones.collider_groups.clear()
assert bpy.ops.tassel.bake(mode="FIXED", frame_start=1, frame_end=1 + FRAMES) == {"FINISHED"}
apart = 0.0
for sample in ref["samples"]:
    scene.frame_set(1 + sample["frame"])
    for j, want in zip(ref["joints"], sample["world_pos"]):
        got = arm.matrix_world @ arm.pose.bones[j["name"]].head
        apart = max(apart, math.dist((-got.x, got.z, got.y), want))
if apart < 1e-3:
    helpers.fail(f"the collider changes nothing ({apart} m)")
print(f"OK VRM 0.x bone group + sphere collider: 4 joints × {FRAMES} frames within {worst:.1e} m of "
      f"tassel simulate of the add-on's VRM 0.x export (without the collider: {apart:.3f} m off)")
