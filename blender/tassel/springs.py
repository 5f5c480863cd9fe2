"""The VRM Add-on for Blender's spring bones as JSON for Tassel (`springs_json`).

The add-on keeps VRM 1.0 springs in `armature.data.vrm_addon_extension.spring_bone1`
(collider offsets in the bone's own Blender frame, gravity in Blender's world) and VRM
0.x's in `...vrm0.secondary_animation` (colliders as empties parented to bones). Tassel
is given the armature's bones in their Blender frames with a root that turns Blender's
world into glTF's (pose.TO_TASSEL), so offsets are written as the add-on holds them and
directions are turned with the root.
"""
import json

import numpy as np

from .pose import TO_TASSEL


def _world_dir(v):
    """A direction in Blender's world as Tassel's (x, z, -y)."""
    return [float(v[0]), float(v[2]), -float(v[1])]


def vrm_extension(armature):
    """The add-on's data on an armature object, or None (the add-on is not installed)."""
    return getattr(armature.data, "vrm_addon_extension", None)


def springs_json(armature, bone_index):
    """JSON text for the armature's VRM spring bones, or None when it has none.
    `bone_index` maps a bone name to its joint index. Raises ValueError naming what is
    wrong (a spring naming a bone the armature does not have)."""
    ext = vrm_extension(armature)
    if ext is None:
        return None
    if str(getattr(ext, "spec_version", "")).startswith("0"):
        doc = _vrm0(armature, ext.vrm0.secondary_animation, bone_index)
    else:
        doc = _vrm1(ext.spring_bone1, bone_index)
    return None if doc is None else json.dumps(doc)


def _bone(bone_index, name, what):
    if name not in bone_index:
        raise ValueError(f"{what} names the bone '{name}', which the armature does not have")
    return bone_index[name]


def _vrm1_shape(collider):
    extended = collider.extensions.vrmc_spring_bone_extended_collider
    if extended.enabled:
        kind = extended.shape_type
        shape = extended.shape
        if kind == extended.SHAPE_TYPE_EXTENDED_SPHERE.identifier:
            s = shape.sphere
            main = {"sphere": {"offset": list(s.offset), "radius": s.radius, "inside": bool(s.inside)}}
        elif kind == extended.SHAPE_TYPE_EXTENDED_CAPSULE.identifier:
            c = shape.capsule
            main = {"capsule": {"offset": list(c.offset), "radius": c.radius, "tail": list(c.tail),
                                "inside": bool(c.inside)}}
        else:
            p = shape.plane
            main = {"plane": {"offset": list(p.offset), "normal": list(p.normal)}}
        fallback = _vrm1_basic_shape(collider, fallback=True)
        return fallback, {"VRMC_springBone_extended_collider": {"specVersion": "1.0", "shape": main}}
    return _vrm1_basic_shape(collider, fallback=False), None


def _vrm1_basic_shape(collider, fallback):
    shape = collider.shape
    if collider.shape_type == collider.SHAPE_TYPE_CAPSULE.identifier:
        c = shape.capsule
        offset = c.fallback_offset if fallback else c.offset
        tail = c.fallback_tail if fallback else c.tail
        radius = c.fallback_radius if fallback else c.radius
        return {"capsule": {"offset": list(offset), "radius": radius, "tail": list(tail)}}
    s = shape.sphere
    offset = s.fallback_offset if fallback else s.offset
    radius = s.fallback_radius if fallback else s.radius
    return {"sphere": {"offset": list(offset), "radius": radius}}


def _vrm1(spring_bone, bone_index):
    if len(spring_bone.springs) == 0:
        return None
    colliders, by_uuid = [], {}
    for i, c in enumerate(spring_bone.colliders):
        shape, extensions = _vrm1_shape(c)
        entry = {"node": _bone(bone_index, c.node.bone_name, f"collider {i} ('{c.name}')"), "shape": shape}
        if extensions:
            entry["extensions"] = extensions
        by_uuid[c.uuid] = len(colliders)
        colliders.append(entry)
    groups, group_by_uuid = [], {}
    for g in spring_bone.collider_groups:
        group_by_uuid[g.uuid] = len(groups)
        groups.append({"name": g.vrm_name, "colliders": [by_uuid[r.collider_uuid] for r in g.colliders
                                                         if r.collider_uuid in by_uuid]})
    springs = []
    for s in spring_bone.springs:
        what = f"spring '{s.vrm_name}'"
        joints = []
        for k, j in enumerate(s.joints):
            joint = {
                "node": _bone(bone_index, j.node.bone_name, what),
                "hitRadius": j.hit_radius,
                "stiffness": j.stiffness,
                "gravityPower": j.gravity_power,
                "gravityDir": _world_dir(j.gravity_dir),
                "dragForce": j.drag_force,
            }
            limit = _vrm1_limit(j, k == len(s.joints) - 1)
            if limit:
                joint["extensions"] = {"VRMC_springBone_limit": limit}
            joints.append(joint)
        spring = {
            "name": s.vrm_name,
            "joints": joints,
            "colliderGroups": [group_by_uuid[r.collider_group_uuid] for r in s.collider_groups
                               if r.collider_group_uuid in group_by_uuid],
        }
        if s.center.bone_name:
            spring["center"] = _bone(bone_index, s.center.bone_name, f"{what}'s center")
        springs.append(spring)
    return {"specVersion": "1.0", "colliders": colliders, "colliderGroups": groups, "springs": springs}


def _vrm1_limit(joint, last):
    """The joint's VRMC_springBone_limit (draft) as the add-on's own exporter writes it."""
    limit = getattr(joint, "vrmc_spring_bone_limit", None)
    if limit is None or last:
        return None
    if limit.limit_type == "CONE":
        kind, fields = "cone", {"angle": limit.cone_angle}
    elif limit.limit_type == "HINGE":
        kind, fields = "hinge", {"angle": limit.hinge_angle}
    elif limit.limit_type == "SPHERICAL":
        kind, fields = "spherical", {"pitch": limit.spherical_pitch, "yaw": limit.spherical_yaw}
    else:
        return None
    q = limit.rotation_quaternion()
    fields["rotation"] = [q.x, q.y, q.z, q.w]
    return {"specVersion": "1.0", "limit": {kind: fields}}


def _vrm0(armature, secondary, bone_index):
    if len(secondary.bone_groups) == 0:
        return None
    world_inverse = np.linalg.inv(np.array(armature.matrix_world))
    groups, group_by_uuid = [], {}
    for i, g in enumerate(secondary.collider_groups):
        node = _bone(bone_index, g.node.bone_name, f"collider group {i}")
        bone = armature.pose.bones[g.node.bone_name]
        bone_inverse = np.linalg.inv(np.array(bone.matrix))
        colliders = []
        for c in g.colliders:
            empty = c.bpy_object
            if empty is None:
                continue
            # The empty's centre in the bone's frame (it rides the bone); Tassel reads a
            # VRM 0.x offset with z negated (Unity's axes), so z is written negated.
            at = bone_inverse @ world_inverse @ np.array(empty.matrix_world)[:, 3]
            scale = float(np.mean(np.abs(np.array(empty.matrix_world.to_scale()))))
            colliders.append({"offset": {"x": float(at[0]), "y": float(at[1]), "z": -float(at[2])},
                              "radius": float(empty.empty_display_size) * scale})
        group_by_uuid[g.uuid] = len(groups)
        groups.append({"node": node, "colliders": colliders})
    bone_groups = []
    for g in secondary.bone_groups:
        what = f"bone group '{g.comment}'"
        entry = {
            "comment": g.comment,
            "stiffiness": g.stiffiness,
            "gravityPower": g.gravity_power,
            "gravityDir": dict(zip("xyz", _world_dir(g.gravity_dir))),
            "dragForce": g.drag_force,
            "hitRadius": g.hit_radius,
            "center": _bone(bone_index, g.center.bone_name, f"{what}'s center") if g.center.bone_name else -1,
            "bones": [_bone(bone_index, b.bone_name, what) for b in g.bones if b.bone_name],
            "colliderGroups": [group_by_uuid[r.collider_group_uuid] for r in g.collider_groups
                               if r.collider_group_uuid in group_by_uuid],
        }
        bone_groups.append(entry)
    return {"boneGroups": bone_groups, "colliderGroups": groups}


__all__ = ["springs_json", "vrm_extension", "TO_TASSEL"]
