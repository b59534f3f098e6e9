# SPDX-License-Identifier: MIT
"""isokit for Blender: bake implicit skinning (isokit) on an armature-deformed mesh.

A panel in the 3D view's sidebar (N, tab "isokit") and in the mesh's Object Data properties, on
a mesh deformed by an armature: method,
setup file, frame range, output (a point cache played by a Mesh Cache modifier, or shape keys)
and "Bake". Every mesh deformed by the same armature bakes with it. docs/blender.md.
"""
import os
import threading

import bpy

from . import core

bl_info = {
    "name": "isokit implicit skinning",
    "author": "isokit",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "3D View > Sidebar > isokit",
    "description": "Bake implicit skinning (Vaillant et al. 2013, 2014) with isokit",
    "category": "Animation",
    "doc_url": "https://example.invalid/isokit/docs/blender.md",
}

_MODULE_ERROR = None


def _module_error():
    """None when `import isokit` works in Blender's Python, else the one-line reason."""
    global _MODULE_ERROR
    try:
        import isokit  # noqa: F401
        from isokit import skinning  # noqa: F401

        _MODULE_ERROR = None
    except ImportError as e:
        _MODULE_ERROR = (f"isokit: the Python module is not importable from Blender's Python ({e}); build and "
                         "install isokit for this Python (docs/blender.md)")
    return _MODULE_ERROR


class IsokitSettings(bpy.types.PropertyGroup):
    method: bpy.props.EnumProperty(
        name="Method",
        items=[("implicit2013", "Implicit (2013)", "Implicit skinning, Vaillant et al. 2013 (isokit's default)"),
               ("tracking2014", "Tracking (2014)", "Iso-surface tracking, Vaillant et al. 2014"),
               ("ddm", "Direct Delta Mush", "Direct Delta Mush, Le & Lewis 2019"),
               ("cor", "Centers of rotation", "Optimized centers of rotation, Le & Hodgins 2016"),
               ("dqs", "Dual quaternions", "Dual-quaternion skinning"),
               ("lbs", "Linear blend", "Linear blend skinning")],
        default=core.DEFAULT_METHOD)
    setup: bpy.props.StringProperty(name="Setup", subtype="FILE_PATH",
                                    description="An isokit setup JSON file (empty: isokit's defaults)")
    use_scene_range: bpy.props.BoolProperty(name="Scene range", default=True)
    frame_start: bpy.props.IntProperty(name="Start", default=1)
    frame_end: bpy.props.IntProperty(name="End", default=250)
    output: bpy.props.EnumProperty(
        name="Output",
        items=[("POINT_CACHE", "Point cache", "A .pc2 beside the .blend, played by a Mesh Cache modifier"),
               ("SHAPE_KEYS", "Shape keys", "One shape key per frame, keyed on its frame")],
        default="POINT_CACHE")


def frame_range(scene):
    s = scene.isokit
    if s.use_scene_range:
        return scene.frame_start, scene.frame_end
    return s.frame_start, s.frame_end


def cache_folder():
    """//isokit beside the saved .blend, else a folder in the system's temp folder."""
    if bpy.data.filepath:
        return os.path.join(os.path.dirname(bpy.data.filepath), "isokit")
    return os.path.join(bpy.app.tempdir or "/tmp", "isokit")


def write_results(scene, arrays, frames, start):
    """Each mesh's frames as its point cache or shape keys; returns the files written."""
    settings = scene.isokit
    written = []
    for obj, a, b in arrays["ranges"]:
        local = core.local_frames(obj, frames[:, a:b])
        if settings.output == "SHAPE_KEYS":
            core.write_shape_keys(obj, local, start)
            continue
        folder = cache_folder()
        os.makedirs(folder, exist_ok=True)
        path = os.path.join(folder, f"{bpy.path.clean_name(obj.name)}.pc2")
        core.write_point_cache(path, local, start, scene.render.fps)
        core.attach_point_cache(obj, path, start)
        written.append(path)
    return written


class ISOKIT_OT_bake(bpy.types.Operator):
    """Bake isokit's skinning of the active mesh (and every mesh on its armature)"""

    bl_idname = "isokit.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH" and core.armature_of(obj) is not None

    def prepare(self, context):
        if _module_error():
            raise core.BakeError(_MODULE_ERROR)
        scene = context.scene
        obj = context.active_object
        self.armature = core.armature_of(obj)
        self.meshes = core.meshes_of(self.armature, scene)
        self.start, self.end = frame_range(scene)
        if self.end < self.start:
            raise core.BakeError(f"the frame range {self.start}-{self.end} is empty; set an end after the start")
        self.arrays = core.read_rig(context, self.meshes, self.armature)

    def finish(self, context, frames):
        written = write_results(context.scene, self.arrays, frames, self.start)
        names = ", ".join(o.name for o in self.meshes)
        self.report({"INFO"}, f"isokit: baked {names}, frames {self.start}-{self.end}"
                              + (f" -> {', '.join(written)}" if written else " as shape keys"))

    def execute(self, context):
        """Blocking bake (scripts and background mode)."""
        try:
            self.prepare(context)
            wm = context.window_manager
            n = self.end - self.start + 1
            wm.progress_begin(0, 2 * n)
            poses = core.read_poses(context.scene, self.armature, self.arrays["joints"], self.arrays["parents"],
                                    range(self.start, self.end + 1))
            frames = core.bake(self.arrays, poses, context.scene.isokit.method,
                               bpy.path.abspath(context.scene.isokit.setup) or None)
            wm.progress_end()
            self.finish(context, frames)
        except (core.BakeError, ValueError, RuntimeError) as e:
            context.window_manager.progress_end()
            self.report({"ERROR"}, " ".join(str(e).split()))
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        """Interactive bake: frames read one per timer tick, then the bake in a thread (isokit
        releases the GIL); Blender's progress bar follows both; Esc cancels."""
        try:
            self.prepare(context)
        except (core.BakeError, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, " ".join(str(e).split()))
            return {"CANCELLED"}
        self.frames = list(range(self.start, self.end + 1))
        self.poses = []
        self.state = {"done": 0, "total": len(self.frames), "cancel": False, "result": None, "error": None}
        self.thread = None
        wm = context.window_manager
        wm.progress_begin(0, 2 * len(self.frames))
        self.timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        wm = context.window_manager
        if event.type == "ESC":
            self.state["cancel"] = True
            if self.thread is None:
                return self.stop(context, "isokit: bake cancelled")
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if len(self.poses) < len(self.frames):  # read one frame per tick
            f = self.frames[len(self.poses)]
            self.poses.append(core.read_poses(context.scene, self.armature, self.arrays["joints"],
                                              self.arrays["parents"], [f])[0])
            wm.progress_update(len(self.poses))
            return {"RUNNING_MODAL"}
        if self.thread is None:
            import numpy as np

            poses = np.stack(self.poses)
            method = context.scene.isokit.method
            setup = bpy.path.abspath(context.scene.isokit.setup) or None
            state = self.state

            def progress(stage, done, total):
                if state["cancel"]:
                    raise KeyboardInterrupt("cancelled")
                if stage.startswith("bake"):
                    state["done"] = done

            def work():
                try:
                    state["result"] = core.bake(self.arrays, poses, method, setup, progress)
                except BaseException as e:  # reported by the modal loop
                    state["error"] = e

            self.thread = threading.Thread(target=work, daemon=True)
            self.thread.start()
            return {"RUNNING_MODAL"}
        wm.progress_update(len(self.frames) + self.state["done"])
        if self.thread.is_alive():
            return {"RUNNING_MODAL"}
        if self.state["error"] is not None:
            e = self.state["error"]
            if isinstance(e, KeyboardInterrupt):
                return self.stop(context, "isokit: bake cancelled")
            return self.stop(context, " ".join(str(e).split()), error=True)
        self.stop(context, None)
        self.finish(context, self.state["result"])
        return {"FINISHED"}

    def stop(self, context, message, error=False):
        wm = context.window_manager
        wm.event_timer_remove(self.timer)
        wm.progress_end()
        if message:
            self.report({"ERROR"} if error else {"WARNING"}, message)
        return {"CANCELLED"}


class ISOKIT_PT_panel(bpy.types.Panel):
    bl_label = "isokit skinning"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "isokit"

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH"

    def draw(self, context):
        layout = self.layout
        if _MODULE_ERROR:
            layout.label(text="isokit module not found", icon="ERROR")
            layout.label(text="See docs/blender.md")
            return
        obj = context.active_object
        arm = core.armature_of(obj)
        if arm is None:
            layout.label(text="Needs an Armature modifier", icon="INFO")
            return
        s = context.scene.isokit
        layout.label(text=f"Armature: {arm.name}")
        layout.prop(s, "method")
        layout.prop(s, "setup")
        layout.prop(s, "use_scene_range")
        if not s.use_scene_range:
            row = layout.row(align=True)
            row.prop(s, "frame_start")
            row.prop(s, "frame_end")
        layout.prop(s, "output", expand=True)
        meshes = core.meshes_of(arm, context.scene)
        layout.label(text=f"{len(meshes)} mesh(es) on this armature")
        layout.operator(ISOKIT_OT_bake.bl_idname, icon="MOD_ARMATURE")


class ISOKIT_PT_data_panel(bpy.types.Panel):
    """The same panel in the Properties editor, Object Data tab of the mesh."""

    bl_label = "isokit skinning"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "data"
    bl_order = -1  # above the mesh's own panels
    poll = ISOKIT_PT_panel.poll
    draw = ISOKIT_PT_panel.draw


_CLASSES = (IsokitSettings, ISOKIT_OT_bake, ISOKIT_PT_panel, ISOKIT_PT_data_panel)


def register():
    for c in _CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.isokit = bpy.props.PointerProperty(type=IsokitSettings)
    if _module_error():
        print(_MODULE_ERROR)


def unregister():
    del bpy.types.Scene.isokit
    for c in reversed(_CLASSES):
        bpy.utils.unregister_class(c)
