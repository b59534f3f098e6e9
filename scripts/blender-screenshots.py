# SPDX-License-Identifier: MIT
# The pictures of docs/blender.md: the add-on's panel and a baked frame (the test's rigged cylinder
# bent 120 degrees, tracking2014), from Blender's own window under Xvfb:
#   blender -b --factory-startup --python-expr "import bpy; bpy.ops.wm.save_as_mainfile(filepath='/tmp/blank.blend')"
#   PYTHONPATH=build/python xvfb-run -a -s "-screen 0 1600x1400x24" \
#     blender --factory-startup /tmp/blank.blend -P scripts/blender-screenshots.py
# writes docs/figures/blender-panel.png and docs/figures/blender-baked.png.
import os
import sys

import bpy
import mathutils

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "apps", "blender"))
sys.path.insert(0, os.path.join(ROOT, "tests", "blender"))
import isokit_blender  # noqa: E402
import test_addon  # noqa: E402

STATE = {}


def window():
    return bpy.context.window_manager.windows[0]


def build():
    bpy.context.preferences.view.ui_scale = 0.8
    with bpy.context.temp_override(window=window()):
        for o in list(bpy.data.objects):
            bpy.data.objects.remove(o)
        scene, obj, arm = test_addon.build_scene(reset=False)
        bpy.context.view_layer.objects.active = obj
        obj.select_set(True)
    STATE.update(scene=scene)
    for area in window().screen.areas:
        if area.type == "VIEW_3D":
            space = area.spaces.active
            space.show_region_ui = False
            region = [r for r in area.regions if r.type == "WINDOW"][0]
            space.region_3d.view_perspective = "PERSP"
            space.region_3d.view_rotation = mathutils.Euler((1.2, 0, 0.9)).to_quaternion()
            with bpy.context.temp_override(window=window(), area=area, region=region):
                bpy.ops.view3d.view_all()
            space.region_3d.view_distance *= 1.1


def shoot():
    import matplotlib.image as image

    with bpy.context.temp_override(window=window()):
        bpy.ops.isokit.bake()
    STATE["scene"].frame_set(25)
    for area in window().screen.areas:
        if area.type == "PROPERTIES":
            area.spaces.active.context = "DATA"
        area.tag_redraw()
    shot = os.path.join(bpy.app.tempdir, "window.png")
    with bpy.context.temp_override(window=window()):
        bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=2)
        bpy.ops.screen.screenshot(filepath=shot)
    a = image.imread(shot)
    f = 1600 / 1176  # crops measured on a 1600 x 1400 window
    image.imsave(os.path.join(ROOT, "docs", "figures", "blender-panel.png"),
                 a[int(720 * f):int(850 * f), int(995 * f):1600])
    image.imsave(os.path.join(ROOT, "docs", "figures", "blender-baked.png"),
                 a[int(330 * f):int(880 * f), int(150 * f):int(700 * f)])
    bpy.ops.wm.quit_blender()


isokit_blender.register()
bpy.app.timers.register(build, first_interval=1.0)
bpy.app.timers.register(shoot, first_interval=3.0)
