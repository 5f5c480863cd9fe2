"""The picture in docs/blender.md: Fox.glb's Run in Blender, before (top row: the clip as
imported, the tail stiff) and after bpy.ops.tassel.bake with examples/rigs/fox.toml
(bottom row: the baked action), at three moments, rendered with Cycles on the CPU.

    python blender/bench/picture.py ZIP docs/images/blender_bake.png
"""
import os
import sys

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import helpers  # noqa: E402

zip_path, out = sys.argv[-2], sys.argv[-1]
MOMENTS = (8, 14, 20)
W, H = 360, 270

helpers.fresh_blender(zip_path)
scene = bpy.context.scene
bpy.ops.import_scene.gltf(filepath=os.path.join(helpers.SHARED, "gltf", "Fox.glb"))
fox = helpers.armature()
run = fox.animation_data.action = bpy.data.actions["Run"]
fox.tassel.rig_file = os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")
bpy.context.view_layer.objects.active = fox
assert bpy.ops.tassel.bake(frame_start=1, frame_end=max(MOMENTS)) == {"FINISHED"}
baked = fox.animation_data.action

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
camera.location = (260.0, 20.0, 60.0)
camera.rotation_euler = (Vector((0.0, 15.0, 35.0)) - camera.location).to_track_quat("-Z", "Y").to_euler()
scene.camera = camera
sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 4.0
sun.rotation_euler = (0.7, 0.2, 1.2)
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("world")
world.color = (0.8, 0.82, 0.85)
scene.world = world
scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 16
scene.render.resolution_x, scene.render.resolution_y = W, H
scene.render.film_transparent = False

tiles = []
for action in (run, baked):
    row = []
    for frame in MOMENTS:
        fox.animation_data.action = action
        scene.frame_set(frame)
        scene.render.filepath = os.path.join(os.path.dirname(os.path.abspath(out)), "_tile.png")
        bpy.ops.render.render(write_still=True)
        image = bpy.data.images.load(scene.render.filepath)
        pixels = np.array(image.pixels[:], dtype=np.float32).reshape(H, W, 4)
        bpy.data.images.remove(image)
        row.append(pixels)
    tiles.append(np.concatenate(row, axis=1))
os.remove(scene.render.filepath)
# Blender's image rows run bottom-up: the first row (the clip as imported) goes on top.
sheet = np.concatenate(tiles[::-1], axis=0)
picture = bpy.data.images.new("sheet", width=sheet.shape[1], height=sheet.shape[0])
picture.pixels = sheet.ravel()
picture.filepath_raw = out
picture.file_format = "PNG"
picture.save()
print(f"wrote {out}: frames {MOMENTS}, top the Run clip, bottom the bake")
