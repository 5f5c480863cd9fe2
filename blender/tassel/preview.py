"""The live preview: while playing (or scrubbing), each armature with `tassel.preview` on
is stepped on every frame change and its simulated bones are posed. The first frame of
the scene's range resets the solvers; the next frame steps 1/fps; any other jump
teleports (the solvers start again from the pose there)."""
import bpy
from bpy.app.handlers import persistent
from mathutils import Matrix

from . import bake, character

# Per armature (by name): the stepper, the last frame stepped, the simulated bones'
# own matrix_basis (put back before the next evaluation, so the pose read is the animation's).
_live = {}


def invalidate(_self=None, _context=None):
    """Forget every preview's state (a setting changed, the preview was switched off):
    the simulated bones get their own transforms back and the next frame starts again."""
    for key, state in _live.items():
        armature = bpy.data.objects.get(key)
        if armature is not None and state["saved"] is not None:
            _restore(armature, state)
        state["stepper"].character.close()
    _live.clear()


def _restore(armature, state):
    for name, basis in zip(state["bones"], state["saved"]):
        bone = armature.pose.bones.get(name)
        if bone is not None:
            bone.matrix_basis = basis
    state["saved"] = None


def _state(armature):
    s = armature.tassel
    key = armature.name
    state = _live.get(key)
    if state is None:
        stepper = bake.Stepper(armature, s.mode, s.step_rate)
        names = [stepper.skeleton.names[j] for j in stepper.character.simulated]
        state = {"stepper": stepper, "last": None, "bones": names, "saved": None}
        _live[key] = state
    return state


def _armatures(scene):
    return [o for o in scene.objects if o.type == "ARMATURE" and o.tassel.preview]


@persistent
def before_frame(scene, _depsgraph=None):
    """Puts the simulated bones' own transforms back before the animation is evaluated."""
    for armature in _armatures(scene):
        state = _live.get(armature.name)
        if state and state["saved"] is not None:
            _restore(armature, state)


@persistent
def after_frame(scene, depsgraph=None):
    """Steps each previewed armature on the evaluated frame and poses its simulated bones
    (not while a bake plays the frames: it reads the animation, which `before_frame` has
    given back)."""
    if bake.BAKING[0]:
        return
    frame = scene.frame_current
    for armature in _armatures(scene):
        try:
            state = _state(armature)
        except (character.RigError, character.native.TasselError) as e:
            armature.tassel.preview = False
            print(f"Tassel preview of '{armature.name}' stopped: {e}")
            continue
        stepper = state["stepper"]
        dt = scene.render.fps_base / scene.render.fps
        if frame == scene.frame_start or state["last"] is None:
            stepper.character.reset()
            dt = 0.0
        elif frame != state["last"] + 1:
            stepper.character.teleport()
        state["last"] = frame
        graph = depsgraph or bpy.context.evaluated_depsgraph_get()
        try:
            out = stepper.step(graph, armature, dt)
        except character.native.TasselError as e:
            print(f"Tassel preview of '{armature.name}': {e}")
            continue
        simulated = stepper.character.simulated
        bases = stepper.skeleton.bases_of(out[simulated], simulated)
        bones = armature.pose.bones
        state["saved"] = [bones[name].matrix_basis.copy() for name in state["bones"]]
        for name, basis in zip(state["bones"], bases):
            bones[name].matrix_basis = Matrix(basis.tolist())


def register():
    bpy.app.handlers.frame_change_pre.append(before_frame)
    bpy.app.handlers.frame_change_post.append(after_frame)


def unregister():
    for handlers, fn in ((bpy.app.handlers.frame_change_pre, before_frame),
                         (bpy.app.handlers.frame_change_post, after_frame)):
        if fn in handlers:
            handlers.remove(fn)
    invalidate()


__all__ = ["register", "unregister", "invalidate"]
