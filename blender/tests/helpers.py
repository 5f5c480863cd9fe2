"""What the Blender tests share: a clean Blender with the extension installed the way a
user installs it, the glTF clip played as glTF defines it, and world points of bones."""
import math
import os
import sys

import bpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.join(ROOT, "..", "shared", "testdata")
TASSEL = os.path.join(ROOT, "target", "release", "tassel")
# Blender's world (x, y, z) is glTF's (x, z, -y); back: glTF (x, y, z) is Blender's (x, -z, y).


def to_gltf(v):
    return (v[0], v[2], -v[1])


def fresh_blender(zip_path, vrm_addon=False):
    """Factory settings, Tassel installed from its zip by Blender's own extension installer
    (and the VRM Add-on for Blender enabled when asked)."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, result
    assert hasattr(bpy.types.Object, "tassel"), "the extension did not register"
    if vrm_addon:
        import addon_utils

        addon_utils.enable("io_scene_vrm", default_set=True)


def armature():
    found = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    assert len(found) == 1, [o.name for o in found]
    return found[0]


def slerp(a, b, u):
    """glTF's LINEAR rotation interpolation (w x y z tuples), shortest path."""
    dot = sum(x * y for x, y in zip(a, b))
    if dot < 0:
        b, dot = [-x for x in b], -dot
    if dot > 0.9995:
        q = [x + u * (y - x) for x, y in zip(a, b)]
    else:
        theta = math.acos(min(1.0, dot))
        s = math.sin(theta)
        wa, wb = math.sin((1 - u) * theta) / s, math.sin(u * theta) / s
        q = [wa * x + wb * y for x, y in zip(a, b)]
    n = math.sqrt(sum(x * x for x in q))
    return [x / n for x in q]


def key_rotations_every_frame(action):
    """Blender interpolates a quaternion's four curves one by one (nlerp); glTF's LINEAR is
    slerp. So the clip plays as the file defines it, every rotation is keyed on every
    whole frame of its range by slerp between the imported keys (the imported keys are
    the file's, turned into the bone's frame by a fixed rotation, which slerp commutes with)."""
    for layer in action.layers:
        for strip in layer.strips:
            for bag in strip.channelbags:
                paths = {fc.data_path for fc in bag.fcurves if fc.data_path.endswith("rotation_quaternion")}
                for path in paths:
                    curves = [bag.fcurves.find(path, index=i) for i in range(4)]
                    keys = [[tuple(k.co) for k in fc.keyframe_points] for fc in curves]
                    times = [k[0] for k in keys[0]]
                    values = [[keys[c][i][1] for c in range(4)] for i in range(len(times))]
                    frames = list(range(math.ceil(times[0]), math.floor(times[-1]) + 1))
                    out = []
                    for f in frames:
                        i = max(0, min(len(times) - 2, next((k for k in range(len(times) - 1) if times[k + 1] >= f), len(times) - 2)))
                        u = 0.0 if times[i + 1] == times[i] else (f - times[i]) / (times[i + 1] - times[i])
                        u = min(1.0, max(0.0, u))
                        out.append(slerp(values[i], values[i + 1], u))
                    for c, fc in enumerate(curves):
                        fc.keyframe_points.clear()
                        fc.keyframe_points.add(len(frames))
                        co = []
                        for f, q in zip(frames, out):
                            co += [f, q[c]]
                        fc.keyframe_points.foreach_set("co", co)
                        fc.update()


def world_points(arm, names):
    """Each bone's world head and tail (Blender's axes)."""
    m = arm.matrix_world
    return {n: (m @ arm.pose.bones[n].head, m @ arm.pose.bones[n].tail) for n in names}


def fail(message):
    print("FAIL", message)
    sys.exit(1)


def gltf_node_names(path):
    """The node names of a GLB/VRM file, read from its JSON chunk."""
    import json
    import struct

    with open(path, "rb") as f:
        data = f.read()
    length = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + length])
    return [n.get("name", f"node{i}") for i, n in enumerate(doc.get("nodes", []))]


def gltf_json(path):
    """A GLB/VRM file's JSON chunk."""
    import json
    import struct

    with open(path, "rb") as f:
        data = f.read()
    length = struct.unpack("<I", data[12:16])[0]
    return json.loads(data[20:20 + length])


def complete_extended_colliders(arm, path):
    """The VRM Add-on for Blender (4.10.2) drops a VRMC_springBone_extended_collider whose
    collider has no `shape` of its own (the fallback the extension asks for; the test
    files leave it out): it imports a tiny far-away sphere instead. Sets the add-on's
    extended-collider properties as the file gives them, in the bone's frame (VRM 1.0
    nodes are not rotated, so a node vector is a world vector). Returns how many."""
    from mathutils import Vector

    doc = gltf_json(path)
    names = [n.get("name") for n in doc["nodes"]]
    fixed = 0
    colliders = arm.data.vrm_addon_extension.spring_bone1.colliders
    for entry, collider in zip(doc["extensions"]["VRMC_springBone"].get("colliders", []), colliders):
        ext = entry.get("extensions", {}).get("VRMC_springBone_extended_collider")
        if ext is None or "shape" in entry:
            continue
        bone = arm.data.bones[names[entry["node"]]]
        to_bone = bone.matrix_local.to_3x3().transposed()

        def local(v):
            return to_bone @ Vector((v[0], -v[2], v[1]))

        extended = collider.extensions.vrmc_spring_bone_extended_collider
        extended.enabled = True
        (kind, shape), = ext["shape"].items()
        if kind == "plane":
            extended.shape_type = extended.SHAPE_TYPE_EXTENDED_PLANE.identifier
            extended.shape.plane.offset = local(shape["offset"])
            extended.shape.plane.normal = local(shape["normal"])
        elif kind == "sphere":
            extended.shape_type = extended.SHAPE_TYPE_EXTENDED_SPHERE.identifier
            extended.shape.sphere.offset = local(shape["offset"])
            extended.shape.sphere.radius = shape["radius"]
            extended.shape.sphere.inside = shape.get("inside", False)
        else:
            extended.shape_type = extended.SHAPE_TYPE_EXTENDED_CAPSULE.identifier
            extended.shape.capsule.offset = local(shape["offset"])
            extended.shape.capsule.tail = local(shape["tail"])
            extended.shape.capsule.radius = shape["radius"]
            extended.shape.capsule.inside = shape.get("inside", False)
        fixed += 1
    return fixed
