"""Speed of a bake in Blender: 1 000 frames of Fox.glb's Run (looped) with
examples/rigs/fox.toml, by bpy.ops.tassel.bake, wall time including the keyframes it
writes; and, given Wiggle 2's add-on file, the same tail bones through its bake. With
`--avatar DEMO_VRM` (from `tassel demo`: 83 bones, 44 of them VRM spring joints,
imported by the VRM Add-on for Blender, swaying), the same for the avatar.

    python blender/bench/bake_fox.py ZIP [WIGGLE_2_PY] [--avatar DEMO_VRM]

Wiggle 2 (github.com/shteeve3d/blender-wiggle-2, GPL) is not part of Tassel: fetch it
yourself and pass its wiggle_2.py. Prints medians of 3 runs.
"""
import os
import statistics
import sys
import time

import bpy

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "tests"))
import helpers  # noqa: E402

FRAMES = 1000
RUNS = 3


def fox_scene(zip_path):
    helpers.fresh_blender(zip_path)
    scene = bpy.context.scene
    scene.render.fps = 24
    scene.frame_start, scene.frame_end = 1, FRAMES
    bpy.ops.import_scene.gltf(filepath=os.path.join(helpers.SHARED, "gltf", "Fox.glb"))
    fox = helpers.armature()
    run = fox.animation_data.action = bpy.data.actions["Run"]
    for bag in run.layers[0].strips[0].channelbags:
        for fc in bag.fcurves:
            fc.modifiers.new("CYCLES")
    bpy.context.view_layer.objects.active = fox
    return scene, fox, run


def avatar_scene(zip_path, vrm):
    """The avatar swaying 0.2 m side to side once a second, for FRAMES frames at 60 fps."""
    import math

    helpers.fresh_blender(zip_path, vrm_addon=True)
    scene = bpy.context.scene
    scene.render.fps = 60
    scene.frame_start, scene.frame_end = 1, FRAMES
    assert bpy.ops.import_scene.vrm(filepath=vrm) == {"FINISHED"}
    arm = helpers.armature()
    for f in range(1, FRAMES + 1):
        arm.location.x = 0.2 * math.sin(2 * math.pi * f / 60)
        arm.keyframe_insert("location", index=0, frame=f)
    bpy.context.view_layer.objects.active = arm
    springs = arm.data.vrm_addon_extension.spring_bone1.springs
    joints = [j.node.bone_name for s in springs for j in list(s.joints)[:-1]]
    return scene, arm, arm.animation_data.action, joints


def tassel(zip_path, scene_of=None):
    scene, fox, run = fox_scene(zip_path) if scene_of is None else scene_of()[:3]
    if scene_of is None:
        fox.tassel.rig_file = os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")
    times = []
    for _ in range(RUNS):
        fox.animation_data.action = run
        t = time.perf_counter()
        assert bpy.ops.tassel.bake(frame_start=1, frame_end=FRAMES) == {"FINISHED"}
        times.append(time.perf_counter() - t)
    keys = sum(len(fc.keyframe_points) for bag in fox.animation_data.action.layers[0].strips[0].channelbags
               for fc in bag.fcurves)
    return statistics.median(times), keys


def wiggle(zip_path, wiggle_py, scene_of=None):
    if scene_of is None:
        scene, fox, run = fox_scene(zip_path)
        chosen = ("b_Tail02_013", "b_Tail03_014")
    else:
        scene, fox, run, chosen = scene_of()
    bpy.ops.preferences.addon_install(filepath=wiggle_py)
    import addon_utils

    addon_utils.enable("wiggle_2", default_set=True)
    scene.wiggle_enable = True
    bpy.ops.object.mode_set(mode="POSE")
    for name in chosen:
        fox.pose.bones[name].wiggle_tail = True
    times = []
    for _ in range(RUNS):
        fox.animation_data.action = run
        for b in fox.pose.bones:
            if hasattr(b, "select"):  # Blender 5: selection is the pose bone's
                b.select = b.name in chosen
            else:
                b.bone.select = b.name in chosen
        t = time.perf_counter()
        assert bpy.ops.wiggle.bake() == {"FINISHED"}
        times.append(time.perf_counter() - t)
    return statistics.median(times)


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:]
    avatar = None
    if "--avatar" in argv:
        i = argv.index("--avatar")
        avatar = argv[i + 1]
        del argv[i:i + 2]
    zip_path, wiggle_py = argv[0], (argv[1] if len(argv) > 1 else None)
    seconds, keys = tassel(zip_path)
    print(f"Fox: tassel baked {FRAMES} frames of Run with fox.toml in {seconds:.3f} s "
          f"(median of {RUNS}; {keys} keys written: 24 bones)")
    if wiggle_py:
        w = wiggle(zip_path, wiggle_py)
        print(f"Fox: Wiggle 2 baked the same {FRAMES} frames, Tail02 and Tail03, in {w:.3f} s "
              f"(median of {RUNS}): {w / seconds:.1f}x tassel's time")
    if avatar:
        def scene_of():
            return avatar_scene(zip_path, avatar)
        seconds, keys = tassel(zip_path, scene_of)
        print(f"avatar: tassel baked {FRAMES} frames of its 44 VRM spring joints in {seconds:.3f} s "
              f"(median of {RUNS}; {keys} keys written)")
        if wiggle_py:
            w = wiggle(zip_path, wiggle_py, scene_of)
            print(f"avatar: Wiggle 2 baked the same {FRAMES} frames, its 44 spring joints wiggling, "
                  f"in {w:.3f} s (median of {RUNS}): {w / seconds:.1f}x tassel's time")
