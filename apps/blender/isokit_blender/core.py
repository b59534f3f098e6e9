# SPDX-License-Identifier: MIT
"""What the add-on reads from Blender and writes back, without any UI (docs/blender.md).

- `read_rig`: the evaluated rest meshes (the Armature modifier off, every other modifier on),
  their vertex groups as weights, and the armature's rest bones, all in world space;
- `read_poses`: the armature's posed bones at each frame as the evaluated scene gives them
  (constraints, IK and drivers included), as local joint transforms;
- `bake`: isokit's bake of those arrays (`isokit.skinning`), frames in world space;
- `write_point_cache` / `attach_point_cache` / `write_shape_keys`: the result on each mesh.
"""
import os
import struct

import numpy as np

try:
    import bpy
except ImportError:  # the arrays part is importable (and tested) without Blender
    bpy = None


class BakeError(Exception):
    """One line for Blender's report area: what is wrong and what to do."""


def armature_of(obj):
    """The armature object deforming `obj` through an enabled Armature modifier, or None."""
    for mod in obj.modifiers:
        if mod.type == "ARMATURE" and mod.object is not None:
            return mod.object
    return None


def meshes_of(armature, scene):
    """Every mesh of the scene deformed by `armature` (they bake together)."""
    return [o for o in scene.objects if o.type == "MESH" and armature_of(o) is armature]


def _matrix(m):
    return np.array([list(row) for row in m], dtype=np.float64)


def _bones_parents_first(armature):
    """The deforming bones, parents before children (Blender lists them so already; kept stable)."""
    bones = [b for b in armature.data.bones if b.use_deform]
    names = {b.name for b in bones}
    order, seen = [], set()

    def visit(b):
        if b.name in seen:
            return
        if b.parent is not None and b.parent.name in names:
            visit(b.parent)
        seen.add(b.name)
        order.append(b)

    for b in bones:
        visit(b)
    return order


def _deforming_parent(bone, names):
    p = bone.parent
    while p is not None and p.name not in names:
        p = p.parent
    return p


MASK_NAME = "_RELAX_MASK"
# Blender 3.4's glTF exporter writes a mesh attribute NAME as the custom attribute "_" + NAME
# upper-cased: an attribute RELAX_MASK reaches the file as _RELAX_MASK. Both names are read.
MASK_NAMES = (MASK_NAME, "RELAX_MASK")


def read_mask(obj, mesh):
    """The painted relaxation mask of one mesh (V,) float32 in [0, 1], or None: a float point
    attribute named _RELAX_MASK or RELAX_MASK, else a vertex group of either name (weight paint;
    unassigned vertices read 1)."""
    n = len(mesh.vertices)
    attr = next((mesh.attributes[k] for k in MASK_NAMES if k in mesh.attributes), None)
    if attr is not None:
        if attr.domain != "POINT" or attr.data_type != "FLOAT":
            raise BakeError(f"mesh '{obj.name}': attribute {attr.name} is {attr.data_type} on {attr.domain}; "
                            "make it a Float attribute on the Vertex (point) domain")
        m = np.empty(n, np.float32)
        attr.data.foreach_get("value", m)
    else:
        group = next((obj.vertex_groups[k] for k in MASK_NAMES if k in obj.vertex_groups), None)
        if group is None:
            return None
        m = np.ones(n, np.float32)
        for v in mesh.vertices:
            for g in v.groups:
                if g.group == group.index:
                    m[v.index] = g.weight
    if not np.all(np.isfinite(m)):
        raise BakeError(f"mesh '{obj.name}': the relaxation mask has values that are not finite; paint 0 .. 1")
    return np.clip(m, 0.0, 1.0)


def read_rig(context, meshes, armature):
    """Arrays of the rig: vertices (V, 3) world, triangles (F, 3), joint names, parents, bind
    world transforms (J, 4, 4), dense weights (V, J), the relaxation mask (V,) or None when no mesh
    has one (read_mask), and per mesh its vertex range."""
    bones = _bones_parents_first(armature)
    if not bones:
        raise BakeError(f"armature '{armature.name}' has no deforming bone")
    names = [b.name for b in bones]
    index = {n: i for i, n in enumerate(names)}
    parents = []
    for b in bones:
        p = _deforming_parent(b, set(names))
        parents.append(-1 if p is None else index[p.name])
    arm_world = _matrix(armature.matrix_world)
    bind_world = np.stack([arm_world @ _matrix(b.matrix_local) for b in bones])

    verts, tris, weights, masks, ranges = [], [], [], [], []
    offset = 0
    for obj in meshes:
        mods = [m for m in obj.modifiers if m.type == "ARMATURE"]
        states = [(m.show_viewport, m.show_render) for m in mods]
        try:
            for m in mods:
                m.show_viewport = False
            context.view_layer.update()
            depsgraph = context.evaluated_depsgraph_get()
            evaluated = obj.evaluated_get(depsgraph)
            mesh = evaluated.to_mesh()
            try:
                n = len(mesh.vertices)
                co = np.empty(n * 3, np.float64)
                mesh.vertices.foreach_get("co", co)
                world = _matrix(evaluated.matrix_world)
                co = co.reshape(n, 3) @ world[:3, :3].T + world[:3, 3]
                mesh.calc_loop_triangles()
                t = np.empty(len(mesh.loop_triangles) * 3, np.int32)
                mesh.loop_triangles.foreach_get("vertices", t)
                w = np.zeros((n, len(names)), np.float32)
                groups = {g.index: g.name for g in obj.vertex_groups}
                for v in mesh.vertices:
                    for g in v.groups:
                        j = index.get(groups.get(g.group, ""))
                        if j is not None and g.weight > 0:
                            w[v.index, j] += g.weight
                masks.append(read_mask(obj, mesh))
            finally:
                evaluated.to_mesh_clear()
        finally:
            for m, (sv, sr) in zip(mods, states):
                m.show_viewport, m.show_render = sv, sr
            context.view_layer.update()
        unweighted = np.flatnonzero(w.sum(axis=1) <= 0)
        if len(unweighted):
            raise BakeError(f"mesh '{obj.name}': {len(unweighted)} vertices (first {unweighted[0]}) have no weight "
                            "on a deforming bone; weight them (or remove them) and bake again")
        verts.append(co)
        tris.append(t.reshape(-1, 3) + offset)
        weights.append(w)
        ranges.append((obj, offset, offset + n))
        offset += n
    return {
        "vertices": np.vstack(verts).astype(np.float32),
        "triangles": np.vstack(tris).astype(np.int32),
        "joints": names,
        "parents": parents,
        "bind_world": bind_world,
        "weights": np.vstack(weights),
        "mask": None if all(m is None for m in masks) else np.concatenate(
            [np.ones(len(v), np.float32) if m is None else m for v, m in zip(verts, masks)]),
        "ranges": ranges,
    }


def read_poses(scene, armature, joints, parents, frames):
    """Local joint transforms (F, J, 4, 4) at each frame, from the evaluated pose bones."""
    current = scene.frame_current
    poses = np.empty((len(frames), len(joints), 4, 4))
    try:
        for k, f in enumerate(frames):
            scene.frame_set(f)
            arm_world = _matrix(armature.matrix_world)
            world = np.stack([arm_world @ _matrix(armature.pose.bones[n].matrix) for n in joints])
            for j, p in enumerate(parents):
                poses[k, j] = world[j] if p < 0 else np.linalg.solve(world[p], world[j])
    finally:
        scene.frame_set(current)
    return poses


# isokit's default method (isokit.skinning.DEFAULT_METHOD, the score's first implicit method:
# docs/decisions/default-method-follows-the-score.md); the add-on's menu starts on it.
DEFAULT_METHOD = "implicit2013"


def bake(arrays, poses, method=None, setup=None, progress=None):
    """isokit's bake of the arrays: frames (F, V, 3) in world space; `method` None: isokit's default."""
    from isokit import skinning

    method = method or skinning.DEFAULT_METHOD
    rig = skinning.Rig.from_arrays(arrays["vertices"], arrays["triangles"], arrays["joints"], arrays["parents"],
                                   arrays["bind_world"], arrays["weights"], name="blender")
    if arrays.get("mask") is not None:
        rig.relax_mask = arrays["mask"]
    skinner = skinning.Skinner(rig, setup=setup or None, progress=progress)
    return skinner.bake(method, poses=poses, self_intersections=False, progress=progress).frames


def write_point_cache(path, frames, start_frame, fps):
    """A PC2 point cache of `frames` (F, V, 3) (Blender's Mesh Cache reads it), written atomically."""
    frames = np.ascontiguousarray(frames, dtype="<f4")
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"POINTCACHE2\0")
        f.write(struct.pack("<iiffi", 1, frames.shape[1], float(start_frame), 1.0, frames.shape[0]))
        f.write(frames.tobytes())
    os.replace(tmp, path)


def local_frames(obj, frames):
    """World-space frames in `obj`'s local space (what a Mesh Cache or a shape key holds)."""
    inv = np.linalg.inv(_matrix(obj.matrix_world))
    return frames @ inv[:3, :3].T + inv[:3, 3]


def attach_point_cache(obj, path, start_frame):
    """Adds (or updates) a Mesh Cache modifier playing `path` and turns the Armature modifier off,
    so that the mesh is not deformed twice."""
    mod = obj.modifiers.get("isokit") or obj.modifiers.new("isokit", "MESH_CACHE")
    mod.cache_format = "PC2"
    mod.filepath = bpy.path.relpath(path) if bpy.data.filepath else path
    mod.frame_start = float(start_frame)
    mod.time_mode = "FRAME"
    mod.play_mode = "SCENE"
    mod.forward_axis = "POS_Y"
    mod.up_axis = "POS_Z"
    for m in obj.modifiers:
        if m.type == "ARMATURE":
            m.show_viewport = False
            m.show_render = False
    return mod


def write_shape_keys(obj, frames, start_frame):
    """One shape key per frame, each keyed to 1 on its frame and 0 on its neighbours."""
    if obj.data.shape_keys is None:
        obj.shape_key_add(name="Basis", from_mix=False)
    keys = []
    for k, f in enumerate(frames):
        key = obj.shape_key_add(name=f"isokit {start_frame + k}", from_mix=False)
        key.data.foreach_set("co", np.ascontiguousarray(f, np.float32).ravel())
        keys.append(key)
    for k, key in enumerate(keys):
        frame = start_frame + k
        for at, value in ((frame - 1, 0.0), (frame, 1.0), (frame + 1, 0.0)):
            key.value = value
            key.keyframe_insert("value", frame=at)
    for m in obj.modifiers:
        if m.type == "ARMATURE":
            m.show_viewport = False
            m.show_render = False
