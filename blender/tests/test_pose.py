"""The extension's pose math (blender/tassel/pose.py, numpy only) against closed forms
and numpy's own linear algebra.

    python test_pose.py
"""
import importlib.util
import math
import os
import sys

import numpy as np

spec = importlib.util.spec_from_file_location(
    "pose", os.path.join(os.path.dirname(__file__), "..", "tassel", "pose.py"))
pose = importlib.util.module_from_spec(spec)
spec.loader.exec_module(pose)
rng = np.random.default_rng(7)


def check(label, ok, detail=""):
    if not ok:
        print("FAIL", label, detail)
        sys.exit(1)
    print("OK", label, detail)


# Quaternions → matrices → quaternions, random and the awkward ones (half turns about
# each axis, where w is 0 and a naive trace formula divides by it).
q = rng.normal(size=(2000, 4))
q /= np.linalg.norm(q, axis=1, keepdims=True)
half_turns = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0.6, 0.8, 0], [0, 0, 0, 1.0]])
q = np.vstack([q, half_turns])
back = pose.quats_from_matrices(pose.matrices_from_quats(q))
same = np.minimum(np.abs(back - q).max(axis=1), np.abs(back + q).max(axis=1))
check("quaternion ↔ matrix round trip", same.max() < 1e-12, f"({same.max():.1e})")
# A matrix of a quarter turn about +Z written by hand: x → y.
rz = np.array([[[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]])
want = np.array([0, 0, math.sin(math.pi / 4), math.cos(math.pi / 4)])
check("a quarter turn about +Z", np.allclose(pose.quats_from_matrices(rz)[0], want))

# Transforms with scale, and a mirror, survive matrices.
t = np.zeros((500, 10))
t[:, 0:3] = rng.normal(size=(500, 3))
t[:, 3:7] = q[:500]
t[:, 7:10] = rng.uniform(0.2, 3.0, size=(500, 3))
t[:50, 7] *= -1
m = pose.matrices_from_transforms(t)
m2 = pose.matrices_from_transforms(pose.transforms_from_matrices(m))
check("transform ↔ matrix round trip (scale, mirror)", np.abs(m2 - m).max() < 1e-9)

inv = pose.affine_inverses(m)
check("affine inverses = numpy's", np.abs(inv - np.linalg.inv(m)).max() < 1e-9)

# Blender's world to Tassel's: up (+Z) becomes +Y, forward (-Y) becomes +Z.
up = pose.TO_TASSEL @ np.array([0, 0, 1.0, 0])
fwd = pose.TO_TASSEL @ np.array([0, -1.0, 0, 0])
check("Blender's +Z is Tassel's +Y, -Y is +Z", np.allclose(up[:3], [0, 1, 0]) and np.allclose(fwd[:3], [0, 0, 1]))
root = pose.root_transform(np.eye(4))
check("the root of an unmoved object is -90° about X",
      min(np.abs(root[3:7] - s * np.array([-math.sqrt(0.5), 0, 0, math.sqrt(0.5)])).max() for s in (1, -1)) < 1e-12
      and np.allclose(root[7:], 1))

# A three-bone chain: locals are parent⁻¹ · child, bases give locals back.
rest = np.stack([np.eye(4)] * 3)
rest[1, :3, 3] = [0, 1, 0]
rest[2, :3, 3] = [0, 2, 0]
skel = pose.Skeleton(["a", "b", "c"], [-1, 0, 1], rest)
check("rest locals of a straight chain", np.allclose(skel.rest[:, 1], [0, 1, 1]) and np.allclose(skel.rest[:, 6], 1))
posed = rest.copy()
posed[1, :3, :3] = pose.matrices_from_quats(np.array([[0, 0, math.sin(0.3), math.cos(0.3)]]))[0]
posed[2, :3, 3] = posed[1, :3, :3] @ np.array([0, 1.0, 0]) + posed[1, :3, 3]
posed[2, :3, :3] = posed[1, :3, :3]
local = skel.pose_locals(posed)
check("posed locals: b turned 0.6 rad about Z, c follows unturned",
      np.allclose(local[1, 3:7], [0, 0, math.sin(0.3), math.cos(0.3)]) and np.allclose(local[2, 3:7], [0, 0, 0, 1])
      and np.allclose(local[2, 0:3], [0, 1, 0]))
frames = skel.pose_locals(np.stack([rest, posed]))
check("many frames at once = one by one", np.allclose(frames[1], local) and np.allclose(frames[0], skel.rest))
bases = skel.bases_of(local)
check("rest_local · basis = local", np.allclose(skel.rest_local_matrices @ bases, pose.matrices_from_transforms(local)))

# A bone scaled to nothing: its matrix and its children's cannot be taken apart; with the
# pose bones' bases given, their locals are rest_local @ basis (the basis's rotation, the
# zero scale kept), and the others are untouched.
turn = pose.matrices_from_quats(np.array([[0, 0, math.sin(0.2), math.cos(0.2)]]))[0]
bases = np.stack([np.eye(4)] * 3)
bases[1, :3, :3] = turn * 0.0  # b: turned 0.4 rad, then scaled to nothing
bases[2, :3, :3] = turn       # c: turned 0.4 rad
collapsed = rest.copy()
collapsed[1, :3, :3] = 0.0
collapsed[2, :3, :3] = 0.0
collapsed[2, :3, 3] = collapsed[1, :3, 3]
fixed = skel.pose_locals(collapsed, bases)
plain = skel.pose_locals(collapsed)
check("a bone scaled to nothing: scale 0 from its basis, a unit rotation",
      np.allclose(fixed[1, 7:10], 0) and abs(np.linalg.norm(fixed[1, 3:7]) - 1) < 1e-12)
check("its child's local from its basis, not from the collapsed matrices",
      np.allclose(fixed[2, 3:7], [0, 0, math.sin(0.2), math.cos(0.2)]) and np.allclose(fixed[2, 0:3], [0, 1, 0])
      and not np.allclose(plain[2, 0:3], [0, 1, 0]))
check("the bones above it untouched", np.allclose(fixed[0], skel.rest[0]))
# Flattened on one axis only: the rotation survives (the other two axes give it).
flat = np.zeros((1, 10))
flat[0, 3:7] = [0, 0, math.sin(0.2), math.cos(0.2)]
flat[0, 7:10] = [1.0, 0.0, 2.0]
back = pose.transforms_from_matrices(pose.matrices_from_transforms(flat))
check("one axis scaled to nothing keeps the rotation", np.allclose(back, flat))
