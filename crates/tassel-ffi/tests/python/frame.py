"""A Python client of Tassel's C ABI through ctypes, run by tests/c_abi.rs.

    python3 frame.py LIBRARY FILE MODE FRAMES DT AMP FREQ

As tests/c/frame.c: loads FILE's bytes (its VRM spring bones), moves the root along x by
AMP * sin(2 pi FREQ t), feeds the rest pose every frame and prints each joint's world
position per frame ("P frame joint x y z"), composed here in Python from the output
locals. Errors (a bad mode, a wrong length, NaN) must come back as values with a message.
"""
import ctypes
import ctypes.util
import math
import sys

import tassel_abi

lib_path, path, mode, frames, dt, amp, freq = sys.argv[1:8]
frames, dt, amp, freq = int(frames), float(dt), float(amp), float(freq)
lib = tassel_abi.open_library(lib_path)
P, FLOATS = tassel_abi.P, tassel_abi.FLOATS

failures = 0


def fail(what):
    global failures
    print("FAIL", what, "(last error:", lib.tassel_last_error(), ")")
    failures += 1


data = open(path, "rb").read()
if lib.tassel_character_load(data, len(data), None, b"sideways"):
    fail("mode 'sideways' loaded")
elif b"sideways" not in (lib.tassel_last_error() or b""):
    fail("the bad mode is not named")
c = lib.tassel_character_load(data, len(data), None, mode.encode())
if not c:
    fail("load")
    sys.exit(1)
n = lib.tassel_joint_count(c)
parents = [lib.tassel_joint_parent(c, j) for j in range(n)]
Floats = ctypes.c_float * (10 * n)
rest, out = Floats(), Floats()
if lib.tassel_rest_locals(c, rest, 10 * n) != 0:
    fail("rest_locals")
bad = Floats(*rest)
bad[3] = float("nan")
root = (ctypes.c_float * 10)()
if lib.tassel_frame(c, root, bad, out, 10 * n, ctypes.c_float(dt)) != -1:
    fail("a NaN frame passed")
if lib.tassel_frame(c, root, rest, out, 10 * n - 1, ctypes.c_float(dt)) != -1:
    fail("a short frame passed")
print("J", n)


def qmul(p, q):
    return (
        p[3] * q[0] + p[0] * q[3] + p[1] * q[2] - p[2] * q[1],
        p[3] * q[1] - p[0] * q[2] + p[1] * q[3] + p[2] * q[0],
        p[3] * q[2] + p[0] * q[1] - p[1] * q[0] + p[2] * q[3],
        p[3] * q[3] - p[0] * q[0] - p[1] * q[1] - p[2] * q[2],
    )


def rotate(q, v):
    u, w = q[:3], q[3]
    c1 = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
    c2 = (u[1] * c1[2] - u[2] * c1[1], u[2] * c1[0] - u[0] * c1[2], u[0] * c1[1] - u[1] * c1[0])
    return tuple(v[i] + 2 * (w * c1[i] + c2[i]) for i in range(3))


def compose(a, b):
    t = rotate(a[1], tuple(a[2][i] * b[0][i] for i in range(3)))
    return (
        tuple(a[0][i] + t[i] for i in range(3)),
        qmul(a[1], b[1]),
        tuple(a[2][i] * b[2][i] for i in range(3)),
    )


def f32(v):
    """`v` rounded to a 32-bit float: the root moves as tassel simulate computes it."""
    return ctypes.c_float(v).value


# The C library's sinf, as Rust's f32::sin calls it on Linux.
libm = ctypes.CDLL(ctypes.util.find_library("m"))
libm.sinf.restype = ctypes.c_float
libm.sinf.argtypes = [ctypes.c_float]
TAU = f32(2 * math.pi)
for f in range(1, frames + 1):
    t = f32(f * f32(dt))
    w = f32(f32(TAU * f32(freq)) * t)
    x = f32(f32(amp) * libm.sinf(w))
    root = (ctypes.c_float * 10)(x, 0, 0, 0, 0, 0, 1, 1, 1, 1)
    if lib.tassel_frame(c, root, rest, out, 10 * n, ctypes.c_float(dt)) != 0:
        fail("frame %d" % f)
    r = (tuple(root[0:3]), tuple(root[3:7]), tuple(root[7:10]))
    world = [None] * n

    def world_of(j):
        if world[j] is None:
            local = (tuple(out[10 * j:10 * j + 3]), tuple(out[10 * j + 3:10 * j + 7]), tuple(out[10 * j + 7:10 * j + 10]))
            parent = r if parents[j] < 0 else world_of(parents[j])
            world[j] = compose(parent, local)
        return world[j]

    for j in range(n):
        p = world_of(j)[0]
        print("P %d %d %.9g %.9g %.9g" % (f, j, p[0], p[1], p[2]))

# The crowd: three characters of the file in one crowd against three characters of their
# own (reset: a crowd member starts from its pose on its first frame), each on its own
# swaying root; the written joints must be the same bits. Member 1 gets a NaN at frame 5:
# held (return 1, listed by tassel_crowd_held, its output not written), the others step.
SIZE_T = ctypes.c_size_t
lib.tassel_crowd_new.restype = P
lib.tassel_crowd_new.argtypes = [P]
lib.tassel_crowd_free.argtypes = [P]
lib.tassel_crowd_add.restype = ctypes.c_ssize_t
lib.tassel_crowd_add.argtypes = [P]
for name in ["read", "written", "held"]:
    count = getattr(lib, "tassel_crowd_%s_count" % name if name == "held" else "tassel_crowd_%s_joint_count" % name)
    count.restype = SIZE_T
    count.argtypes = [P]
    fill = getattr(lib, "tassel_crowd_held" if name == "held" else "tassel_crowd_%s_joints" % name)
    fill.restype = ctypes.c_int32
    fill.argtypes = [P, ctypes.POINTER(SIZE_T), SIZE_T]
lib.tassel_crowd_frame.restype = ctypes.c_int32
lib.tassel_crowd_frame.argtypes = [P, FLOATS, SIZE_T, FLOATS, SIZE_T, FLOATS, SIZE_T, ctypes.c_float]
lib.tassel_crowd_kind.restype = ctypes.c_char_p
lib.tassel_crowd_kind.argtypes = [P]
lib.tassel_reset.argtypes = [P]


def index_list(count, fill, cr):
    k = count(cr)
    arr = (SIZE_T * max(k, 1))()
    if fill(cr, arr, k) != 0:
        fail("index list")
    return list(arr[:k])


if lib.tassel_crowd_new(None):
    fail("a crowd of NULL")
cr = lib.tassel_crowd_new(c)
if lib.tassel_crowd_kind(cr) != b"vrm":
    fail("a VRM file's crowd is not on the VRM crowd path: %r" % lib.tassel_crowd_kind(cr))
members = 3
if [lib.tassel_crowd_add(cr) for _ in range(members)] != [0, 1, 2]:
    fail("crowd indices")
read = index_list(lib.tassel_crowd_read_joint_count, lib.tassel_crowd_read_joints, cr)
written = index_list(lib.tassel_crowd_written_joint_count, lib.tassel_crowd_written_joints, cr)
own = []
for i in range(members):
    ch = lib.tassel_character_load(data, len(data), None, mode.encode())
    lib.tassel_reset(ch)
    own.append(ch)
Roots = ctypes.c_float * (10 * members)
Ins = ctypes.c_float * (10 * members * len(read))
Outs = ctypes.c_float * (10 * members * len(written))
cout = Outs(*([7.0] * (10 * members * len(written))))
if lib.tassel_crowd_frame(cr, Roots(), 10 * members - 1, Ins(), len(Ins()), cout, len(cout), ctypes.c_float(dt)) != -1:
    fail("a short crowd frame passed")
crowd_bits = 0
for f in range(1, 31):
    roots = Roots()
    ins = Ins()
    for i in range(members):
        x = f32(i + 0.3 * math.sin(2 * math.pi * f * dt + i))
        roots[10 * i:10 * i + 10] = [x, 0, 0, 0, 0, 0, 1, 1, 1, 1]
        for k, j in enumerate(read):
            at = 10 * (i * len(read) + k)
            ins[at:at + 10] = rest[10 * j:10 * j + 10]
    nan = f == 5
    if nan:
        ins[10 * (1 * len(read)) + 3] = float("nan")
    before = list(cout)
    code = lib.tassel_crowd_frame(cr, roots, len(roots), ins, len(ins), cout, len(cout), ctypes.c_float(dt))
    if code != (1 if nan else 0):
        fail("crowd frame %d returned %d" % (f, code))
    if nan:
        if index_list(lib.tassel_crowd_held_count, lib.tassel_crowd_held, cr) != [1]:
            fail("the held member is not listed")
        if b"character 1" not in (lib.tassel_last_error() or b""):
            fail("the held member is not named")
    for i in range(members):
        one_root = (ctypes.c_float * 10)(*roots[10 * i:10 * i + 10])
        one = Floats(*rest)
        if nan and i == 1:
            one[10 * read[0] + 3] = float("nan")
        ok = lib.tassel_frame(own[i], one_root, one, one, 10 * n, ctypes.c_float(dt)) == 0
        for k, j in enumerate(written):
            at = 10 * (i * len(written) + k)
            got = cout[at:at + 10]
            want = one[10 * j:10 * j + 10] if ok else before[at:at + 10]
            if got != want:
                fail("crowd frame %d member %d joint %d: %r != %r" % (f, i, j, got, want))
            crowd_bits += 1
print("CROWD", crowd_bits)
for ch in own:
    lib.tassel_character_free(ch)
lib.tassel_crowd_free(cr)

lib.tassel_character_free(c)
print("DONE", failures)
sys.exit(1 if failures else 0)
