"""Tassel for Blender: bake secondary motion (VRM spring bones, KawaiiPhysics-style
chains, cloth, ropes) onto an armature with Tassel's native library.

The panel is in the armature's Object Data properties ("Tassel"); the operator is
`bpy.ops.tassel.bake(mode='FIXED', frame_start=S, frame_end=E, step_rate=60)`.
"""
import bpy

from . import bake, character, preview


def _changed(_self, _context):
    preview.invalidate()


class TasselSettings(bpy.types.PropertyGroup):
    """Tassel's settings on an armature object."""

    rig_file: bpy.props.StringProperty(
        name="Rig File", subtype="FILE_PATH", update=_changed,
        description="A rig file (TOML): chains, springs, cloths, ropes, colliders",
    )
    rig_text: bpy.props.PointerProperty(
        name="Rig Text", type=bpy.types.Text, update=_changed,
        description="A text block holding the rig (TOML); used instead of the file",
    )
    use_vrm_springs: bpy.props.BoolProperty(
        name="VRM Spring Bones", default=True, update=_changed,
        description="Also run the spring bones the VRM Add-on for Blender holds (VRM 1.0 and 0.x)",
    )
    mode: bpy.props.EnumProperty(name="Mode", default="FIXED", update=_changed, items=character.MODE_ITEMS)
    step_rate: bpy.props.FloatProperty(
        name="Step Rate", default=60.0, min=10.0, max=1000.0, update=_changed,
        description="Fixed mode: VRM spring steps per second (chains step at their rig's target_framerate)",
    )
    use_scene_range: bpy.props.BoolProperty(name="Scene Range", default=True)
    frame_start: bpy.props.IntProperty(name="Start", default=1)
    frame_end: bpy.props.IntProperty(name="End", default=250)
    preview: bpy.props.BoolProperty(
        name="Live Preview", default=False, update=_changed,
        description="Step the simulation on every frame change during playback",
    )


class TASSEL_PT_armature(bpy.types.Panel):
    """Tassel on the armature's Object Data tab."""

    bl_label = "Tassel"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"

    @classmethod
    def poll(cls, context):
        return context.object is not None and context.object.type == "ARMATURE"

    def draw(self, context):
        layout = self.layout
        obj = context.object
        s = obj.tassel
        col = layout.column()
        col.prop(s, "rig_file")
        col.prop(s, "rig_text")
        row = col.row()
        row.prop(s, "use_vrm_springs")
        ext = getattr(obj.data, "vrm_addon_extension", None)
        if ext is not None:
            count = len(ext.spring_bone1.springs) or len(ext.vrm0.secondary_animation.bone_groups)
            row.label(text=f"{count} VRM spring{'s' if count != 1 else ''}")
        col.prop(s, "mode")
        col.prop(s, "step_rate")
        col.prop(s, "use_scene_range")
        if not s.use_scene_range:
            row = col.row(align=True)
            row.prop(s, "frame_start")
            row.prop(s, "frame_end")
        col.prop(s, "preview")
        scene = context.scene
        start, end = (scene.frame_start, scene.frame_end) if s.use_scene_range else (s.frame_start, s.frame_end)
        op = col.operator(bake.TASSEL_OT_bake.bl_idname, icon="ACTION")
        op.mode, op.step_rate, op.frame_start, op.frame_end = s.mode, s.step_rate, start, end


_classes = (TasselSettings, bake.TASSEL_OT_bake, TASSEL_PT_armature)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.tassel = bpy.props.PointerProperty(type=TasselSettings)
    preview.register()


def unregister():
    preview.unregister()
    del bpy.types.Object.tassel
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)


__all__ = ["register", "unregister", "character"]
