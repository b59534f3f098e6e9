#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""docs/figures/muscle-biceps.png: the procedural arm (isokit's cylinder) bent 0 -> 90 -> 0 degrees
with tracking2014, without (top row) and with (bottom row) the biceps of docs/skinning.md
"Muscles", seen from the side; the bottom row is coloured by how far the biceps moved the skin.

    PYTHONPATH=build/python /usr/bin/python3 scripts/muscle-figure.py [OUT.png]
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402

from figure_poses import bend_poses  # noqa: E402  (scripts/)
from isokit import skinning  # noqa: E402

BICEPS = {"version": 1, "muscles": [
    {"name": "biceps", "bone": "Bone0", "driver": "Bone1", "center": [0, 0.6, 0.12],
     "radii": [0.3, 0.14, 0.14], "scale_axes": "yz", "curve": [[0, 1], [90, 1.8]]}]}
FRAMES = (0, 5, 10, 15, 20)  # 0, 45, 90, 45, 0 degrees



def draw(ax, pos, tris, colour):
    """The mesh seen along -x (y up, z to the right), back faces culled, painter's order."""
    p = pos[tris]  # (F, 3, 3)
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    front = n[:, 0] > 0
    depth = p[front][:, :, 0].mean(axis=1)
    order = np.argsort(depth)
    shade = np.clip(n[front][:, 0] / np.linalg.norm(n[front], axis=1), 0, 1)[order]
    faces = p[front][order][:, :, [2, 1]]
    rgb = colour[front][order] * (0.35 + 0.65 * shade[:, None])
    ax.add_collection(PolyCollection(faces, facecolors=rgb, edgecolors="none"))
    ax.set_xlim(-0.45, 1.45)
    ax.set_ylim(-0.4, 2.35)
    ax.set_aspect("equal")
    ax.axis("off")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "docs/figures/muscle-biceps.png"
    rig = skinning.load("procedural:cylinder")
    poses = bend_poses(rig, "Bone1", 90, 21)
    plain = skinning.Skinner(rig).bake("tracking2014", poses=poses, self_intersections=False).frames
    biceps = skinning.Skinner(rig, setup=BICEPS).bake("tracking2014", poses=poses, self_intersections=False).frames
    tris = rig.triangles
    grey = np.full((len(tris), 3), 0.8)
    moved = np.linalg.norm(biceps - plain, axis=2)  # (F, V)
    scale = max(moved.max(), 1e-9)
    fig, axes = plt.subplots(2, len(FRAMES), figsize=(2.0 * len(FRAMES), 5.6))
    for c, f in enumerate(FRAMES):
        draw(axes[0, c], plain[f], tris, grey)
        heat = plt.cm.magma_r(moved[f][tris].mean(axis=1) / scale)[:, :3] * 0.85 + 0.15
        draw(axes[1, c], biceps[f], tris, heat)
        degrees = 90 * (1 - abs(2 * f / 20 - 1))
        axes[0, c].set_title(f"{degrees:.0f}°", fontsize=10)
    axes[0, 0].text(-0.4, 2.2, "without", fontsize=9)
    axes[1, 0].text(-0.4, 2.2, "with the biceps", fontsize=9)
    fig.suptitle(f"tracking2014, the biceps moved the skin by up to {scale:.3f} (radius 0.3)", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
