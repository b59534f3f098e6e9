#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Pictures of folds (docs/skinning-metrics.md, "Folds"): the folded triangles of some methods'
bakes drawn red (isokit.skinning.folded_triangles: turned by more than 90 degrees from their rest
normal carried by the skinning blend), both sides of every triangle drawn (back faces blue), so a
crease that faces backward shows.

    PYTHONPATH=build/python python3 scripts/folds-figure.py [OUT.png]
        the procedural cylinder bent to 150 degrees by lbs and dqs (docs/figures/folds-cylinder-150.png)
    PYTHONPATH=build/python python3 scripts/folds-figure.py OUT.png --rig R.glb --clip NAME
        [--methods dqs implicit2013 ...] [--frame K] [--view x|y|z|-x|-y|-z] [--section] [--zoom F] [--rest-map AXIS]
        one frame of a clip (default: the frame where the first method folds the most)
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

from figure_poses import bend_poses  # noqa: E402  (scripts/)
from isokit import skinning  # noqa: E402

FRONT, BACK, FOLDED = np.array([0.82, 0.70, 0.58]), np.array([0.35, 0.45, 0.80]), np.array([0.9, 0.1, 0.1])
AXES = {"x": 0, "y": 1, "z": 2}



def projection(view):
    """(depth axis, sign, the two image axes) of a view along +-x, y or z."""
    sign = -1.0 if view.startswith("-") else 1.0
    d = AXES[view.lstrip("-")]
    u, v = [k for k in range(3) if k != d]
    if d == 1:  # looking down y: x right, z up
        u, v = 0, 2
    return d, sign, u, v


def draw(ax, pos, tris, folded, view, box, section):
    """Every triangle, both sides, painter's order along the view; folded ones red. With `section`,
    the near half of the mesh (along the view) is cut away, so the inside of a fold shows."""
    d, sign, u, v = projection(view)
    if section:
        centre = 0.5 * (pos[:, d].min() + pos[:, d].max())
        keep = sign * (pos[tris][:, :, d].mean(axis=1) - centre) > 0
        tris, folded = tris[keep], folded[keep]
    p = pos[tris]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.maximum(np.linalg.norm(n, axis=1), 1e-30)
    facing = -sign * n[:, d] / length  # > 0: the front side is seen
    colour = np.where(facing[:, None] > 0, FRONT, BACK)
    colour[folded] = FOLDED
    shade = 0.35 + 0.65 * np.abs(facing)
    order = np.argsort(sign * p[:, :, d].mean(axis=1))[::-1]  # far first
    faces = p[order][:, :, [u, v]]
    ax.add_collection(PolyCollection(faces, facecolors=colour[order] * shade[order, None], edgecolors="none"))
    lo, hi = box
    ax.set_xlim(lo[u], hi[u])
    ax.set_ylim(lo[v], hi[v])
    ax.set_aspect("equal")
    ax.axis("off")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", nargs="?", default="docs/figures/folds-cylinder-150.png")
    ap.add_argument("--rig", default=None)
    ap.add_argument("--clip", default=None)
    ap.add_argument("--methods", nargs="+", default=None)
    ap.add_argument("--frame", type=int, default=None)
    ap.add_argument("--view", default=None)
    ap.add_argument("--section", action="store_true", help="cut the near half away (default for the cylinder)")
    ap.add_argument("--rest-map", default=None,
                    help="a second row: the rest mesh seen along this axis, the frame's folds red")
    ap.add_argument("--zoom", type=float, default=0,
                    help="frame the first method's folds, this many times their size (0: the whole mesh)")
    a = ap.parse_args()
    if a.rig:
        rig = skinning.load(a.rig)
        poses = rig.clip_poses(a.clip or rig.clips[0])
        methods = a.methods or ["dqs", "implicit2013"]
        view, title = a.view or "-z", f"{rig.name} {a.clip or rig.clips[0]}"
    else:
        rig = skinning.load("procedural:cylinder")
        poses = bend_poses(rig, "Bone1", 150, 11)
        methods = a.methods or ["lbs", "dqs"]
        view, title = a.view or "x", "the cylinder bent to 150°, cut in half"
        a.section = True
        a.zoom = a.zoom or 3.0
        a.rest_map = a.rest_map or "-z"  # from the inside of the bend
    skinner = skinning.Skinner(rig)
    bakes = {m: skinner.bake(m, poses=poses, self_intersections=False).frames for m in methods}
    folds = {m: skinning.folded_triangles(rig, bakes[m], poses) for m in methods}
    frame = a.frame if a.frame is not None else int(np.argmax(folds[methods[0]].sum(axis=1)))
    everything = np.concatenate([bakes[m][frame] for m in methods])
    pad = 0.05 * np.linalg.norm(everything.max(0) - everything.min(0))
    box = (everything.min(0) - pad, everything.max(0) + pad)
    if a.zoom:  # a close-up of the first method's folds
        hot = bakes[methods[0]][frame][rig.triangles[folds[methods[0]][frame]]].reshape(-1, 3)
        if len(hot):
            centre, half = 0.5 * (hot.min(0) + hot.max(0)), 0.5 * a.zoom * np.linalg.norm(hot.max(0) - hot.min(0))
            half = max(half, 0.1 * np.linalg.norm(everything.max(0) - everything.min(0)))
            box = (centre - half, centre + half)
    rows = 2 if a.rest_map else 1
    fig, axes = plt.subplots(rows, len(methods), figsize=(3.6 * len(methods), 3.6 * rows), squeeze=False)
    for ax, m in zip(axes[0], methods):
        draw(ax, bakes[m][frame], rig.triangles, folds[m][frame], view, box, a.section)
        ax.set_title(f"{m}: {int(folds[m][frame].sum())} folded", fontsize=10)
    if a.rest_map:  # where they are: the rest mesh seen from `rest_map`, the frame's folds red
        rest = rig.rest
        rbox = (rest.min(0) - pad, rest.max(0) + pad)
        for ax, m in zip(axes[1], methods):
            draw(ax, rest, rig.triangles, folds[m][frame], a.rest_map, rbox, False)
            ax.set_title(f"{m}: the same triangles at rest", fontsize=9)
    fig.suptitle(f"{title}, frame {frame} (red: folded; blue: a back face seen)", fontsize=10)
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
