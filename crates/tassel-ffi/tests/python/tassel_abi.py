"""The C ABI's common functions declared for ctypes: what frame.py and skeleton.py share."""
import ctypes

P = ctypes.c_void_p
FLOATS = ctypes.POINTER(ctypes.c_float)


def open_library(path):
    """Tassel's shared library at `path`, its character functions declared."""
    lib = ctypes.CDLL(path)
    lib.tassel_character_load.restype = P
    lib.tassel_character_load.argtypes = [ctypes.c_char_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_char_p]
    lib.tassel_character_new.restype = P
    lib.tassel_character_new.argtypes = [
        ctypes.POINTER(ctypes.c_char_p), ctypes.POINTER(ctypes.c_int32), FLOATS, ctypes.c_size_t,
        ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p,
    ]
    lib.tassel_character_free.argtypes = [P]
    lib.tassel_joint_count.restype = ctypes.c_size_t
    lib.tassel_joint_count.argtypes = [P]
    lib.tassel_joint_parent.restype = ctypes.c_int32
    lib.tassel_joint_parent.argtypes = [P, ctypes.c_size_t]
    lib.tassel_joint_name.restype = ctypes.c_char_p
    lib.tassel_joint_name.argtypes = [P, ctypes.c_size_t]
    lib.tassel_rest_locals.restype = ctypes.c_int32
    lib.tassel_rest_locals.argtypes = [P, FLOATS, ctypes.c_size_t]
    lib.tassel_frame.restype = ctypes.c_int32
    lib.tassel_frame.argtypes = [P, FLOATS, FLOATS, FLOATS, ctypes.c_size_t, ctypes.c_float]
    lib.tassel_last_error.restype = ctypes.c_char_p
    return lib
