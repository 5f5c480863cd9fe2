"""A Python client of tassel_character_new through ctypes, run by tests/c_abi.rs.

    python3 skeleton.py LIBRARY FILE SPRINGS_JSON MODE FRAMES

As tests/c/skeleton.c: loads FILE, takes the joints' names, parents and rest pose it
reports, makes a second character from them and the file's springs JSON with
tassel_character_new, steps both on a swaying root and requires the same bytes out
("SAME <frames>"); a repeated name must be refused with a message naming it.
"""
import ctypes
import math
import sys

import tassel_abi

lib_path, path, json_path, mode, frames = sys.argv[1:6]
frames = int(frames)
lib = tassel_abi.open_library(lib_path)
P, FLOATS = tassel_abi.P, tassel_abi.FLOATS

data = open(path, "rb").read()
springs = open(json_path, "rb").read()
a = lib.tassel_character_load(data, len(data), None, mode.encode())
if not a:
    print("FAIL load:", lib.tassel_last_error())
    sys.exit(1)
n = lib.tassel_joint_count(a)
names = [lib.tassel_joint_name(a, j) for j in range(n)]
Names = ctypes.c_char_p * n
Parents = ctypes.c_int32 * n
Floats = ctypes.c_float * (10 * n)
parents = Parents(*[lib.tassel_joint_parent(a, j) for j in range(n)])
rest = Floats()
if lib.tassel_rest_locals(a, rest, 10 * n) != 0:
    print("FAIL rest:", lib.tassel_last_error())
    sys.exit(1)
b = lib.tassel_character_new(Names(*names), parents, rest, n, None, springs, mode.encode())
if not b:
    print("FAIL new:", lib.tassel_last_error())
    sys.exit(1)
out_a, out_b = Floats(), Floats()
for f in range(frames):
    t = f / 60.0
    root = (ctypes.c_float * 10)(0.3 * math.sin(2 * t), 0, 0, 0, 0, 0, 1, 1, 1, 1)
    dt = 0.2 if f == frames // 2 else 1 / 60
    if lib.tassel_frame(a, root, rest, out_a, 10 * n, dt) != 0 or lib.tassel_frame(b, root, rest, out_b, 10 * n, dt) != 0:
        print("FAIL frame", f, lib.tassel_last_error())
        sys.exit(1)
    if bytes(out_a) != bytes(out_b):
        print("FAIL frame", f, "differs")
        sys.exit(1)
if n >= 2:
    repeated = list(names)
    repeated[1] = repeated[0]
    if lib.tassel_character_new(Names(*repeated), parents, rest, n, None, springs, mode.encode()):
        print("FAIL a repeated name was taken")
        sys.exit(1)
    if b"repeats the name" not in (lib.tassel_last_error() or b""):
        print("FAIL the repeated name is not named:", lib.tassel_last_error())
        sys.exit(1)
lib.tassel_character_free(a)
lib.tassel_character_free(b)
print("SAME", frames)
