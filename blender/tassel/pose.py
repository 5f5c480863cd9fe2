"""An armature as Tassel sees it, and the pose through it both ways (numpy, no bpy).

Tassel's world is glTF's (+Y up); Blender's is +Z up. The character's root transform is
`TO_TASSEL @ object.matrix_world`, so a bone's local transforms, rest or posed, are
Blender's own numbers: a rig file's offsets are in the bone's frame, as Blender's glTF
importer keeps it (bone frame = node frame), and gravity [0, -9.81, 0] points down the
scene's -Z. Transforms for Tassel are 10 floats: tx ty tz qx qy qz qw sx sy sz.
"""
import numpy as np

# Blender world (x, y, z) -> Tassel's (x, z, -y): a quarter turn about +X.
TO_TASSEL = np.array(
    [[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
)


def quats_from_matrices(r):
    """Unit quaternions (x, y, z, w) of rotation matrices r (n × 3 × 3)."""
    m00, m01, m02 = r[:, 0, 0], r[:, 0, 1], r[:, 0, 2]
    m10, m11, m12 = r[:, 1, 0], r[:, 1, 1], r[:, 1, 2]
    m20, m21, m22 = r[:, 2, 0], r[:, 2, 1], r[:, 2, 2]
    squares = np.stack(
        [1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22, 1 + m00 + m11 + m22], axis=1
    )
    pick = np.argmax(squares, axis=1)
    big = 0.5 * np.sqrt(np.maximum(squares[np.arange(len(r)), pick], 1e-30))
    inv = 0.25 / big
    q = np.empty((len(r), 4))
    # Each row from its largest component (the stable one), as Shepperd's method.
    cases = [
        (big, (m01 + m10) * inv, (m02 + m20) * inv, (m21 - m12) * inv),
        ((m01 + m10) * inv, big, (m12 + m21) * inv, (m02 - m20) * inv),
        ((m02 + m20) * inv, (m12 + m21) * inv, big, (m10 - m01) * inv),
        ((m21 - m12) * inv, (m02 - m20) * inv, (m10 - m01) * inv, big),
    ]
    for k, (x, y, z, w) in enumerate(cases):
        rows = pick == k
        q[rows] = np.stack([x[rows], y[rows], z[rows], w[rows]], axis=1)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def matrices_from_quats(q):
    """Rotation matrices (n × 3 × 3) of quaternions q (n × 4, x y z w)."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    r = np.empty((len(q), 3, 3))
    r[:, 0, 0] = 1 - 2 * (y * y + z * z)
    r[:, 0, 1] = 2 * (x * y - z * w)
    r[:, 0, 2] = 2 * (x * z + y * w)
    r[:, 1, 0] = 2 * (x * y + z * w)
    r[:, 1, 1] = 1 - 2 * (x * x + z * z)
    r[:, 1, 2] = 2 * (y * z - x * w)
    r[:, 2, 0] = 2 * (x * z - y * w)
    r[:, 2, 1] = 2 * (y * z + x * w)
    r[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return r


def transforms_from_matrices(m):
    """n × 10 transforms from affine matrices m (n × 4 × 4); shear is dropped, a mirror
    goes into the x scale."""
    lin = m[:, :3, :3]
    scale = np.linalg.norm(lin, axis=1)
    flat = scale <= 1e-12
    rot = lin / np.where(flat, 1.0, scale)[:, None, :]
    # An axis scaled to nothing: the other two still give the rotation (their cross
    # product stands in for it); with two or three gone, no rotation is left (identity).
    for axis in range(3):
        rows = flat[:, axis] & (flat.sum(axis=1) == 1)
        a, b = (axis + 1) % 3, (axis + 2) % 3
        rot[rows, :, axis] = np.cross(rot[rows, :, a], rot[rows, :, b])
    lost = flat.sum(axis=1) >= 2
    rot[lost] = np.eye(3)
    scale = np.where(flat, 0.0, scale)
    mirrored = np.linalg.det(rot) < 0
    scale[mirrored, 0] *= -1
    rot[mirrored, :, 0] *= -1
    out = np.empty((len(m), 10))
    out[:, 0:3] = m[:, :3, 3]
    out[:, 3:7] = quats_from_matrices(rot)
    out[:, 7:10] = scale
    return out


def matrices_from_transforms(t):
    """Affine matrices (n × 4 × 4) of n × 10 transforms."""
    q = t[:, 3:7] / np.linalg.norm(t[:, 3:7], axis=1, keepdims=True)
    m = np.zeros((len(t), 4, 4))
    m[:, :3, :3] = matrices_from_quats(q) * t[:, None, 7:10]
    m[:, :3, 3] = t[:, 0:3]
    m[:, 3, 3] = 1.0
    return m


def affine_inverses(m):
    """Inverses of affine matrices m (… × 4 × 4) by the 3 × 3 adjugate: one batch of
    arithmetic, where numpy's general inverse pays per matrix."""
    a = m[..., :3, :3]
    cof = np.empty_like(a)
    cof[..., 0, 0] = a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 1]
    cof[..., 0, 1] = a[..., 0, 2] * a[..., 2, 1] - a[..., 0, 1] * a[..., 2, 2]
    cof[..., 0, 2] = a[..., 0, 1] * a[..., 1, 2] - a[..., 0, 2] * a[..., 1, 1]
    cof[..., 1, 0] = a[..., 1, 2] * a[..., 2, 0] - a[..., 1, 0] * a[..., 2, 2]
    cof[..., 1, 1] = a[..., 0, 0] * a[..., 2, 2] - a[..., 0, 2] * a[..., 2, 0]
    cof[..., 1, 2] = a[..., 0, 2] * a[..., 1, 0] - a[..., 0, 0] * a[..., 1, 2]
    cof[..., 2, 0] = a[..., 1, 0] * a[..., 2, 1] - a[..., 1, 1] * a[..., 2, 0]
    cof[..., 2, 1] = a[..., 0, 1] * a[..., 2, 0] - a[..., 0, 0] * a[..., 2, 1]
    cof[..., 2, 2] = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    det = np.einsum("...j,...j->...", a[..., 0, :], cof[..., :, 0])
    det = np.where(np.abs(det) > 1e-30, det, 1e-30)
    out = np.zeros_like(m)
    out[..., :3, :3] = cof / det[..., None, None]
    out[..., :3, 3] = -np.einsum("...ij,...j->...i", out[..., :3, :3], m[..., :3, 3])
    out[..., 3, 3] = 1.0
    return out


class Skeleton:
    """An armature's bones as Tassel joints, in the armature's bone order.

    `names`, `parents` (-1 for a root) and `rest_matrices` (n × 4 × 4, each bone's
    `matrix_local`: armature space) come from bpy in `from_armature`."""

    def __init__(self, names, parents, rest_matrices):
        self.names = list(names)
        self.parents = np.asarray(parents, dtype=np.intp)
        self.rest_matrices = np.asarray(rest_matrices, dtype=np.float64).reshape(-1, 4, 4)
        self.has_parent = self.parents >= 0
        self.rest_local_matrices = self.locals_of(self.rest_matrices)
        self.rest_local_inverses = affine_inverses(self.rest_local_matrices)
        self.rest = transforms_from_matrices(self.rest_local_matrices)

    def locals_of(self, armature_matrices):
        """Local matrices (relative to the parent bone) of armature-space matrices
        (… × n × 4 × 4: one pose, or many frames of poses)."""
        m = armature_matrices
        local = m.copy()
        kids = np.nonzero(self.has_parent)[0]
        local[..., kids, :, :] = affine_inverses(m[..., self.parents[kids], :, :]) @ m[..., kids, :, :]
        return local

    def pose_locals(self, pose_matrices, bases=None):
        """Local transforms (… × n × 10) of evaluated poses (`pose.bones[i].matrix`,
        … × n × 4 × 4). Where a matrix cannot be taken apart — a bone scaled to nothing
        (animators hide parts so), or a bone under one — and `bases` (the pose bones'
        `matrix_basis`, the same shape) is given, that bone's local transform is
        `rest_local @ basis` instead: the animation's own value, without constraints
        (a bone scaled to nothing on two or three axes keeps no rotation: identity)."""
        local = self.locals_of(pose_matrices)
        out = transforms_from_matrices(local.reshape(-1, 4, 4)).reshape(local.shape[:-2] + (10,))
        if bases is None:
            return out
        det = np.abs(np.linalg.det(pose_matrices[..., :3, :3]))
        flat = np.max(np.abs(pose_matrices[..., :3, :3]), axis=(-1, -2))
        degenerate = det <= 1e-9 * np.maximum(flat, 1e-30) ** 3
        bad = degenerate.copy()
        bad[..., self.has_parent] |= degenerate[..., self.parents[self.has_parent]]
        if not bad.any():
            return out
        basis = transforms_from_matrices(bases[bad])
        scale = basis[:, 7:10].copy()
        basis[:, 7:10] = 1.0
        rest = np.broadcast_to(self.rest_local_matrices, local.shape)[bad]
        fixed = transforms_from_matrices(rest @ matrices_from_transforms(basis))
        fixed[:, 7:10] = scale
        out[bad] = fixed
        return out

    def bases_of(self, locals10, joints=None):
        """Pose-bone `matrix_basis` (× 4 × 4) giving the local transforms `locals10` of
        `joints` (default: every bone): local = rest_local @ basis (bones that inherit
        rotation and scale, as by default)."""
        inverses = self.rest_local_inverses if joints is None else self.rest_local_inverses[joints]
        return inverses @ matrices_from_transforms(np.asarray(locals10, dtype=np.float64))


def root_transform(object_world):
    """The character's root for Tassel (10 floats) from the object's matrix_world (4 × 4)."""
    return transforms_from_matrices((TO_TASSEL @ np.asarray(object_world, dtype=np.float64))[None])[0]
