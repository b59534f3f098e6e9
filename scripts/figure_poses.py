"""Poses shared by the figure scripts (scripts/*-figure.py): a joint bent and back."""
import numpy as np


def bend_poses(rig, joint, degrees, frames):
    """Rest -> `degrees` about the joint's local x -> rest, `frames` poses (an isokit.skinning.Rig)."""
    rest = rig.rest_pose()
    poses = np.repeat(rest[None], frames, axis=0)
    j = rig.joints.index(joint)
    for f in range(frames):
        a = np.radians(degrees) * (1 - abs(2 * f / (frames - 1) - 1))
        r = np.eye(4)
        r[1:3, 1:3] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        poses[f, j] = rest[j] @ r
    return poses
