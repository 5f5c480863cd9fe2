"""Fox.glb imported by Blender's glTF importer, examples/rigs/fox.toml, its Run clip baked
over 120 frames with bpy.ops.tassel.bake, in `fixed` and `classic` modes: every bone's world head and tail on every frame
equals `tassel bake` of the same file and rig (read back through Blender's importer) to
1e-4 m. The fox is modelled in centimetres (fox.toml), so that is 0.01 of its units; the
two imports of the animation alone (the file's and tassel bake's re-encoded one) differ by
up to about 7e-5 units, and the simulated bones by about 1.5e-4.

    python test_fox.py ZIP
"""
import os
import subprocess
import sys
import tempfile

import bpy

sys.path.insert(0, os.path.dirname(__file__))
import helpers  # noqa: E402

FOX = os.path.join(helpers.SHARED, "gltf", "Fox.glb")
RIG = os.path.join(helpers.ROOT, "examples", "rigs", "fox.toml")
FPS = 120  # The clip's keys (1/24 s apart, the last at 139/120 s) all land on whole frames.
FRAMES = 120
TOLERANCE = 0.01  # 1e-4 m in the fox's centimetre units

def check(mode, cli_mode):
    """One mode: the bake against `tassel bake --mode` of the same file and rig."""
    helpers.fresh_blender(sys.argv[-1])
    if getattr(bpy.types, "TASSEL_PT_armature", None) is None or bpy.types.TASSEL_PT_armature.bl_context != "data":
        helpers.fail("the panel is not registered on the armature's Object Data tab")
    scene = bpy.context.scene
    scene.render.fps, scene.render.fps_base = FPS, 1.0

    # Tassel's own bake of the file, as the reference.
    reference = os.path.join(tempfile.mkdtemp(), "fox_run.glb")
    subprocess.run([helpers.TASSEL, "bake", FOX, "--rig", RIG, "--clip", "Run", "--fps", str(FPS),
                    "--warmup", "0", "--mode", cli_mode, "-o", reference], check=True, stdout=subprocess.DEVNULL)

    bpy.ops.import_scene.gltf(filepath=FOX)
    fox = helpers.armature()
    fox.animation_data.action = bpy.data.actions["Run"]
    helpers.key_rotations_every_frame(bpy.data.actions["Run"])
    fox.tassel.rig_file = RIG
    bpy.context.view_layer.objects.active = fox
    before = set(bpy.data.actions.keys())
    result = bpy.ops.tassel.bake(mode=mode, frame_start=0, frame_end=FRAMES)
    assert result == {"FINISHED"}, result
    baked = fox.animation_data.action
    if baked.name in before or not bpy.data.actions["Run"].use_fake_user:
        helpers.fail("the bake did not write a new action and keep the source with a fake user")
    # Every bone keyed on every frame.
    for bone in fox.pose.bones:
        fc = baked.fcurve_ensure_for_datablock(fox, f'pose.bones["{bone.name}"].rotation_quaternion', index=0)
        if len(fc.keyframe_points) != FRAMES + 1:
            helpers.fail(f"{bone.name} has {len(fc.keyframe_points)} rotation keys, not {FRAMES + 1}")

    names = [b.name for b in fox.pose.bones]
    fox.name = "baked_by_blender"
    bpy.ops.import_scene.gltf(filepath=reference)
    ref = [o for o in scene.objects if o.type == "ARMATURE" and o != fox][0]
    run = ref.animation_data.action = [a for a in bpy.data.actions if a.name.startswith("Run") and a not in (bpy.data.actions["Run"], baked)][0]
    helpers.key_rotations_every_frame(run)
    simulated = ["b_Tail02_013", "b_Tail03_014"]
    worst = {}
    for f in range(FRAMES + 1):
        scene.frame_set(f)
        ours, theirs = helpers.world_points(fox, names), helpers.world_points(ref, names)
        for n in names:
            for k in (0, 1):
                err = (ours[n][k] - theirs[n][k]).length
                worst[n] = max(worst.get(n, 0.0), err)
    bad = {n: e for n, e in worst.items() if e > TOLERANCE}
    if bad:
        helpers.fail(f"bones differ from tassel bake by more than {TOLERANCE}: {bad}")
    # The tail did swing: the bake is not the animated pose (a bake that wrote the clip back
    # would pass the comparison above only if tassel bake did nothing too).
    fox.animation_data.action = bpy.data.actions["Run"]
    swing = 0.0
    for f in range(FRAMES + 1):
        scene.frame_set(f)
        animated = helpers.world_points(fox, simulated)
        fox.animation_data.action = baked
        scene.frame_set(f)
        swung = helpers.world_points(fox, simulated)
        fox.animation_data.action = bpy.data.actions["Run"]
        swing = max(swing, max((swung[n][1] - animated[n][1]).length for n in simulated))
    if swing < 1.0:
        helpers.fail(f"the tail's tip moves at most {swing} units off the animation: nothing swung")
    print(f"OK Fox Run, {cli_mode}: {FRAMES + 1} frames, {len(names)} bones; the tail swings up to {swing:.1f} units "
          f"off the clip; simulated bones within {max(worst[n] for n in simulated):.2e} units of tassel bake "
          f"(animated bones within {max(e for n, e in worst.items() if n not in simulated):.2e})")


# fixed (the default), and classic (KawaiiPhysics 1.10, frame by frame). Not kawaii here:
# its steps land where KawaiiPhysics' f32 accumulator puts them, and at 120 fps a frame's
# time is half a step, so whether a step lands on an even or an odd frame turns on the
# last bit of the frame time (Blender's 1/120 against tassel bake's differences of key
# times): the two clocks step on different frames. It is held to its f64 port instead
# (crates/tassel/tests/kawaii_1_21.rs).
for mode, cli_mode in (("FIXED", "fixed"), ("CLASSIC", "classic")):
    check(mode, cli_mode)
