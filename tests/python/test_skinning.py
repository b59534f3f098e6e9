# SPDX-License-Identifier: MIT
"""isokit.skinning from Python: rigs, clips, bakes; a Python bake equals the CLI's bit for bit."""
import os
import subprocess

import numpy as np
import pytest

import isokit

skinning = pytest.importorskip("isokit.skinning", reason="isokit built without the skinning library")
CLI = os.environ.get("ISOKIT_SKIN_EXE", "")


def bend_poses(rig, joint, degrees, frames):
    """Local transforms bending `joint` about x from rest to `degrees`."""
    rest = rig.rest_pose()
    poses = np.repeat(rest[None], frames, axis=0)
    j = rig.joints.index(joint)
    for f in range(frames):
        a = np.radians(degrees) * f / (frames - 1)
        r = np.eye(4)
        r[1:3, 1:3] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
        poses[f, j] = rest[j] @ r
    return poses


@pytest.fixture(scope="module")
def cylinder_file(tmp_path_factory):
    rig = skinning.load("procedural:cylinder")
    rig.add_clip("bend", bend_poses(rig, "Bone1", 90, 9))
    path = tmp_path_factory.mktemp("rig") / "cylinder.glb"
    rig.save(path)
    return path


def test_a_rig_and_its_clips(cylinder_file):
    rig = skinning.load(cylinder_file)
    assert rig.joints == ["Bone0", "Bone1"] and rig.parents == [-1, 0]
    assert rig.clips == ["bend"]
    assert rig.rest.shape[1] == 3 and rig.triangles.shape[1] == 3
    poses = rig.clip_poses("bend")
    assert poses.shape == (9, 2, 4, 4)
    assert np.allclose(poses[0], rig.rest_pose(), atol=1e-6)
    assert rig.summary()["clips"] == [("bend", 9, 30.0)]


def test_bakes_with_every_method_give_frames_and_metrics(cylinder_file):
    rig = skinning.load(cylinder_file)
    stages = []
    skinner = skinning.Skinner(rig, progress=lambda stage, done, total: stages.append(stage))
    assert stages
    for method in ("lbs", "dqs", "ddm", "cor", "implicit2013", "tracking2014"):
        result = skinner.bake(method, clip="bend", self_intersections=False)
        assert result.method == method
        frames = result.frames
        assert frames.shape == (9, len(rig.rest), 3) and frames.dtype == np.float32
        assert np.abs(frames[0] - rig.rest).max() < 1e-3
        m = result.metrics()
        assert method in m["methods"] and len(m["methods"][method]["frames"]) == 9
        assert all(f["self_overlap_new"] >= 0 for f in m["methods"][method]["frames"])
        # the skin-only metrics: the cylinder has no rigid piece, so its skin is the whole mesh
        assert all(f["skin_overlap_new"] == f["self_overlap_new"] for f in m["methods"][method]["frames"])
        assert all(f["folded_new"] >= 0 and f["folded_triangles"] >= f["folded_new"]
                   for f in m["methods"][method]["frames"])
        assert m["methods"][method]["frames"][0]["folded_new"] == 0
    # the bake reports each frame; an exception in the callback stops it
    seen = []
    skinner.bake("dqs", clip="bend", progress=lambda stage, done, total: seen.append((stage, done, total)))
    assert seen[-1] == ("bake dqs", 9, 9)

    def stop(stage, done, total):
        raise RuntimeError("stop the bake")

    with pytest.raises(RuntimeError, match="stop the bake"):
        skinner.bake("tracking2014", clip="bend", progress=stop)
    # poses from NumPy and bends give the same kind of result
    result = skinner.bake("dqs", poses=bend_poses(rig, "Bone1", 45, 4))
    assert result.frames.shape[0] == 4
    result = skinner.bake("dqs", bends=["Bone1:x:60"], frames=5)
    assert result.frames.shape[0] == 5


def test_the_overlap_volume_of_two_boxes_through_each_other():
    def box(lo, hi):
        v = np.array([[hi[0] if k & 1 else lo[0], hi[1] if k & 2 else lo[1], hi[2] if k & 4 else lo[2]]
                      for k in range(8)], np.float32)
        f = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                      [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]], np.int32)
        return v, f

    (va, fa), (vb, fb) = box((0, 0, 0), (1, 1, 1)), box((0.5, 0, 0), (1.5, 1, 1))
    v, f = np.vstack([va, vb]), np.vstack([fa, fb + 8])
    r = skinning.self_overlap(v, f, mark_triangles=True)
    assert r["overlap"] == pytest.approx(0.5, rel=0.02)
    assert r["enclosed"] == pytest.approx(1.5, rel=0.02)
    assert r["open_columns"] == 0 and len(r["triangles"]) > 0
    # pressed onto one face: nothing enclosed twice
    vb2, _ = box((1, 0, 0), (2, 1, 1))
    assert skinning.self_overlap(np.vstack([va, vb2]), f)["overlap"] < 1e-12
    with pytest.raises(isokit.InputError, match="resolution"):
        skinning.self_overlap(v, f, resolution=0)


@pytest.mark.skipif(not CLI, reason="isokit-skin not built")
@pytest.mark.parametrize("method", ["dqs", "tracking2014"])
def test_a_python_bake_equals_the_cli_bake_bit_for_bit(cylinder_file, tmp_path, method):
    cli_pc2 = tmp_path / "cli.pc2"
    subprocess.run(
        [CLI, "bake", str(cylinder_file), "--clip", "bend", "--method", method, "--pc2", str(cli_pc2), "--out",
         str(tmp_path / "cli.glb")],
        check=True,
        capture_output=True,
    )
    rig = skinning.load(cylinder_file)
    result = skinning.Skinner(rig).bake(method, clip="bend")
    result.write_pc2(tmp_path / "py.pc2")
    assert (tmp_path / "py.pc2").read_bytes() == cli_pc2.read_bytes()
    result.write_glb(tmp_path / "py.glb")
    assert (tmp_path / "py.glb").read_bytes() == (tmp_path / "cli.glb").read_bytes()


def test_errors_are_input_errors_with_the_cli_messages(tmp_path):
    with pytest.raises(isokit.InputError, match="does not exist"):
        skinning.load(tmp_path / "missing.glb")
    rig = skinning.load("procedural:cylinder")
    skinner = skinning.Skinner(rig)
    with pytest.raises(isokit.InputError, match="lbs, dqs"):
        skinner.bake("magic", bends=["Bone1:x:30"])
    with pytest.raises(isokit.InputError, match="argument 'poses'"):
        skinner.bake("dqs", poses=np.zeros((3, 5, 4, 4)))
    with pytest.raises(isokit.InputError):
        skinner.bake("dqs", clip="none")


def test_a_rig_from_arrays_skins_as_the_same_rig_loaded_from_a_file(cylinder_file):
    loaded = skinning.load(cylinder_file)
    # The cylinder's bind pose: Bone0 at the origin, Bone1 one unit up (procedural.h).
    world = np.repeat(np.eye(4)[None], 2, axis=0)
    world[1, 1, 3] = 1.0
    rest_local = loaded.rest_pose()
    assert np.allclose(world[1], rest_local[0] @ rest_local[1])
    weights = np.zeros((len(loaded.rest), 2), np.float32)
    y = loaded.rest[:, 1]
    weights[:, 1] = np.clip((y - 0.8) / 0.4, 0, 1)
    weights[:, 0] = 1 - weights[:, 1]
    rig = skinning.Rig.from_arrays(loaded.rest, loaded.triangles, ["Bone0", "Bone1"], [-1, 0], world, weights)
    assert rig.joints == ["Bone0", "Bone1"] and np.allclose(rig.rest_pose(), rest_local, atol=1e-6)
    frames = skinning.Skinner(rig).bake("dqs", bends=["Bone1:x:90"], frames=3).frames
    top = y > 1.5
    # The top ring turned 90 degrees about x around (0, 1, 0): y - 1 -> -(z), z -> y - 1.
    assert np.allclose(frames[1][top, 1] - 1, -loaded.rest[top, 2], atol=1e-4)
    with pytest.raises(isokit.InputError, match="parents first"):
        skinning.Rig.from_arrays(loaded.rest, loaded.triangles, ["A", "B"], [1, -1], world, weights)
    with pytest.raises(isokit.InputError, match="argument 'weights'"):
        skinning.Rig.from_arrays(loaded.rest, loaded.triangles, ["A", "B"], [-1, 0], world, weights[:, :1])


def test_the_relaxation_mask_is_read_written_and_holds_vertices_rigid(cylinder_file, tmp_path):
    rig = skinning.load(cylinder_file)
    assert rig.relax_mask is None
    tip = rig.rest[:, 1] > np.percentile(rig.rest[:, 1], 80)  # the far end, on Bone1 alone
    mask = np.where(tip, 0.0, 1.0)  # float64: converted
    rig.relax_mask = mask
    assert rig.relax_mask.dtype == np.float32 and np.array_equal(rig.relax_mask, mask.astype(np.float32))
    # A glb round trip keeps it (the glTF attribute _RELAX_MASK).
    rig.save(tmp_path / "masked.glb")
    back = skinning.load(tmp_path / "masked.glb")
    assert back.relax_mask is not None and back.relax_mask.min() == 0.0 and back.relax_mask.max() == 1.0
    held = skinning.Skinner(rig).bake("tracking2014", clip="bend", self_intersections=False).frames
    diag = np.linalg.norm(rig.rest.max(0) - rig.rest.min(0))

    def shape_change(frames):  # largest change of a distance between two tip vertices
        p = frames[:, tip].astype(np.float64)
        d = np.linalg.norm(p[:, :, None] - p[:, None, :], axis=-1)
        return np.abs(d - d[0]).max()

    assert shape_change(held) <= 1e-5 * diag  # moved rigidly (by its nearest bone)
    rig.relax_mask = None
    assert rig.relax_mask is None
    with pytest.raises(isokit.InputError, match="relax_mask"):
        rig.relax_mask = np.zeros(3)
    with pytest.raises(isokit.InputError, match=r"relax_mask\[0\]"):
        rig.relax_mask = np.full(len(rig.rest), 2.0)


def test_folded_triangles_agree_with_the_metrics(cylinder_file):
    rig = skinning.load(cylinder_file)
    poses = bend_poses(rig, "Bone1", 160, 5)
    skinner = skinning.Skinner(rig)
    for method in ("lbs", "dqs"):
        result = skinner.bake(method, poses=poses, self_intersections=False)
        flags = skinning.folded_triangles(rig, result.frames, poses)
        assert flags.shape == (5, len(rig.triangles)) and flags.dtype == np.bool_
        frames = result.metrics()["methods"][method]["frames"]
        assert [int(f.sum()) for f in flags] == [f["folded_new"] for f in frames]
        assert not flags[0].any()
    assert skinning.folded_triangles(rig, skinner.bake("lbs", poses=poses).frames, poses)[-1].any()
    with pytest.raises(ValueError, match="one pose per frame"):
        skinning.folded_triangles(rig, result.frames, poses[:2])
    assert skinning.DEFAULT_METHOD == "implicit2013"
