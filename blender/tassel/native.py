"""Tassel's C ABI (libtassel_ffi) through ctypes: a character made from a skeleton.

Pure Python and numpy, no bpy: the tests and the benchmark use it outside Blender too.
"""
import ctypes
import os
import sys

import numpy as np

_P = ctypes.c_void_p
_FLOATS = ctypes.POINTER(ctypes.c_float)
_SIZES = ctypes.POINTER(ctypes.c_size_t)

# The functions used here: (return type, argument types), as tassel.h declares them.
_SIGNATURES = {
    "tassel_character_new": (_P, [ctypes.POINTER(ctypes.c_char_p), ctypes.POINTER(ctypes.c_int32), _FLOATS,
                                  ctypes.c_size_t, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p]),
    "tassel_character_free": (None, [_P]),
    "tassel_frame": (ctypes.c_int32, [_P, _FLOATS, _FLOATS, _FLOATS, ctypes.c_size_t, ctypes.c_float]),
    "tassel_reset": (None, [_P]),
    "tassel_teleport": (None, [_P]),
    "tassel_simulated_joint_count": (ctypes.c_size_t, [_P]),
    "tassel_simulated_joints": (ctypes.c_int32, [_P, _SIZES, ctypes.c_size_t]),
    "tassel_mode": (ctypes.c_char_p, [_P]),
    "tassel_last_error": (ctypes.c_char_p, []),
    "tassel_version": (ctypes.c_char_p, []),
}

_LIBRARY_NAMES = {"linux": "libtassel_ffi.so", "darwin": "libtassel_ffi.dylib", "win32": "tassel_ffi.dll"}


class TasselError(Exception):
    """A call into Tassel failed; the message is Tassel's own (it names the joint or key)."""


def library_path():
    """The native library shipped beside this file (TASSEL_LIBRARY overrides it)."""
    override = os.environ.get("TASSEL_LIBRARY")
    if override:
        return override
    name = _LIBRARY_NAMES.get(sys.platform, "libtassel_ffi.so")
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), name)


_lib = None


def library():
    """The loaded library, its functions declared (loaded once)."""
    global _lib
    if _lib is not None:
        return _lib
    path = library_path()
    if not os.path.exists(path):
        raise TasselError(f"Tassel's native library is missing: {path} (build the extension with blender/build.sh)")
    lib = ctypes.CDLL(path)
    for name, (restype, argtypes) in _SIGNATURES.items():
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes
    _lib = lib
    return lib


def _error(what):
    message = library().tassel_last_error()
    return TasselError(f"{what}: {message.decode('utf-8', 'replace') if message else 'unknown error'}")


def _floats(array):
    return array.ctypes.data_as(_FLOATS)


class Character:
    """A Tassel character from a skeleton: `names` (unique), `parents` (-1 for a root),
    `rest` (n × 10 floats: tx ty tz qx qy qz qw sx sy sz, local), a rig's TOML text and/or
    VRM spring bones as JSON text, and a mode ("fixed", "spec", "three-vrm", "classic")."""

    def __init__(self, names, parents, rest, rig_toml=None, springs_json=None, mode="fixed"):
        lib = library()
        n = len(names)
        rest = np.ascontiguousarray(rest, dtype=np.float32).reshape(n, 10)
        c_names = (ctypes.c_char_p * n)(*[name.encode("utf-8") for name in names])
        c_parents = (ctypes.c_int32 * n)(*[int(p) for p in parents])
        handle = lib.tassel_character_new(
            c_names, c_parents, _floats(rest), n,
            rig_toml.encode("utf-8") if rig_toml is not None else None,
            springs_json.encode("utf-8") if springs_json is not None else None,
            mode.encode("utf-8") if mode else None,
        )
        if not handle:
            raise _error("Tassel could not make the character")
        self._handle = handle
        self.joint_count = n
        count = lib.tassel_simulated_joint_count(handle)
        joints = (ctypes.c_size_t * count)()
        if lib.tassel_simulated_joints(handle, joints, count) != 0:
            raise _error("tassel_simulated_joints")
        self.simulated = np.array(joints[:], dtype=np.intp)
        self.mode = lib.tassel_mode(handle).decode()
        self._root = np.zeros(10, dtype=np.float32)

    def frame(self, root, locals_in, locals_out, dt):
        """One frame: `root` (10 floats, the character's world transform), `locals_in`
        (n × 10, float32, C-contiguous) in, `locals_out` (the same shape) out, `dt` seconds."""
        self._root[:] = root
        rc = library().tassel_frame(
            self._handle, _floats(self._root), _floats(locals_in), _floats(locals_out),
            self.joint_count * 10, float(dt),
        )
        if rc != 0:
            raise _error("tassel_frame")

    def reset(self):
        """The next frame starts every solver again from the animated pose."""
        library().tassel_reset(self._handle)

    def teleport(self):
        """The character jumped: the next frame starts again from the pose at the new place."""
        library().tassel_teleport(self._handle)

    def close(self):
        """Frees the native character (also done when the object is collected)."""
        if getattr(self, "_handle", None):
            library().tassel_character_free(self._handle)
            self._handle = None

    def __del__(self):
        self.close()
