# SPDX-License-Identifier: MIT
"""isokit.tracker from Python: tracking isokit fields and fields written in NumPy."""
import numpy as np
import pytest

import isokit
from isokit import fields, tracker


def uv_sphere(rings=12, segments=24):
    """A closed UV sphere of radius 1, triangles counter-clockwise seen from outside."""
    verts = [[0, 0, 1]]
    for i in range(1, rings):
        t = np.pi * i / rings
        for j in range(segments):
            p = 2 * np.pi * j / segments
            verts.append([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
    verts.append([0, 0, -1])
    tris = []
    for j in range(segments):
        tris.append([0, 1 + j, 1 + (j + 1) % segments])
    for i in range(rings - 2):
        a, b = 1 + i * segments, 1 + (i + 1) * segments
        for j in range(segments):
            j1 = (j + 1) % segments
            tris.append([a + j, b + j, b + j1])
            tris.append([a + j, b + j1, a + j1])
    last = len(verts) - 1
    base = 1 + (rings - 2) * segments
    for j in range(segments):
        tris.append([last, base + (j + 1) % segments, base + j])
    return np.array(verts, np.float32), np.array(tris, np.int32)


def ball(radius, width=0.5):
    """A ball written in NumPy with isokit's convention: 0.5 on the sphere, inward gradient."""

    def f(p):
        r = np.linalg.norm(p, axis=1)
        v = np.clip(0.5 + (radius - r) / (2 * width), 0, 1)
        inside = (v > 0) & (v < 1)
        g = np.where(inside[:, None], -p / (2 * width * np.maximum(r, 1e-9)[:, None]), 0)
        return v.astype(np.float32), g.astype(np.float32)

    return f


def turns_about_z(count, angle=0.3):
    """`count` copies of the rotation by `angle` radians about z: targets that slide a sphere round."""
    c, s = np.cos(angle), np.sin(angle)
    rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], np.float32)
    return np.repeat(rz[None], count, axis=0)


def test_a_numpy_field_is_tracked_from_one_thread_with_whole_batches():
    rest, tris = uv_sphere()
    iso = tracker.sample_iso_values(ball(1.0), rest)
    assert np.abs(iso - 0.5).max() < 1e-5
    t = tracker.Tracker(rest, tris, iso)
    calls = []

    def grown(p):
        calls.append(len(p))
        return ball(1.25)(p)

    out, stats = t.track(grown, rest)
    assert out.shape == rest.shape and out.dtype == np.float32
    assert np.abs(np.linalg.norm(out, axis=1) - 1.25).max() < 1e-3
    assert stats["python_field_calls"] == len(calls) > 0
    assert stats["python_field_points"] == sum(calls)
    assert stats["max_residual"] < 1e-3
    assert stats["lost_vertices"] == 0


def test_an_isokit_field_is_tracked_and_agrees_with_the_same_field_in_numpy():
    rest, tris = uv_sphere()
    iso = tracker.sample_iso_values(fields.sphere([0, 0, 0], 1.0), rest)
    t = tracker.Tracker(rest, tris, iso)
    out, stats = t.track(fields.sphere([0.1, 0, 0], 1.2), rest)
    assert np.abs(np.linalg.norm(out - [0.1, 0, 0], axis=1) - 1.2).max() < 2e-3
    assert stats["python_field_calls"] == 0
    assert set(t.flags) == {"contact", "lost", "beta", "free"}


def test_the_tracker_keeps_the_mesh_on_a_moving_field_frame_after_frame():
    rest, tris = uv_sphere()
    iso = np.full(len(rest), 0.5, np.float32)
    t = tracker.Tracker(rest, tris, iso, max_iterations=50)
    p = rest
    for k in range(1, 4):
        c = np.array([0.1 * k, 0, 0])
        p, stats = t.track(lambda q: ball(1.0)(q - c.astype(np.float32)), p + [0.1, 0, 0])
        assert np.abs(np.linalg.norm(p - c, axis=1) - 1.0).max() < 2e-3


def test_errors_from_a_python_field_reach_the_caller():
    rest, tris = uv_sphere()
    t = tracker.Tracker(rest, tris, np.full(len(rest), 0.5))

    def broken(p):
        raise RuntimeError("my field failed")

    with pytest.raises(RuntimeError, match="my field failed"):
        t.track(broken, rest)
    with pytest.raises(isokit.InputError, match="gradients returned by the field"):
        t.track(lambda p: (np.zeros(len(p)), np.zeros((len(p), 2))), rest)
    with pytest.raises(isokit.InputError, match="must return"):
        t.track(lambda p: np.zeros(len(p)), rest)
    with pytest.raises(isokit.InputError, match="argument 'field'"):
        t.track(42, rest)


def test_bad_arrays_and_options_give_one_line_errors():
    rest, tris = uv_sphere()
    iso = np.full(len(rest), 0.5)
    with pytest.raises(isokit.InputError, match=r"argument 'rest': expected shape \(N, 3\)"):
        tracker.Tracker(rest[:, :2], tris, iso)
    with pytest.raises(isokit.InputError, match=r"argument 'iso': expected shape"):
        tracker.Tracker(rest, tris, iso[:-1])
    with pytest.raises(isokit.InputError, match="not a tracker option"):
        tracker.Tracker(rest, tris, iso, magic=1)
    t = tracker.Tracker(rest, tris, iso)
    with pytest.raises(isokit.InputError, match="argument 'positions'"):
        t.track(fields.sphere([0, 0, 0], 1), rest[:-1])
    with pytest.raises(isokit.InputError, match="argument 'rotations'"):
        t.track(fields.sphere([0, 0, 0], 1), rest, rotations=np.zeros((3, 3)))


def test_the_mask_holds_masked_vertices_in_their_tangent_plane_and_applies_per_call():
    rest, tris = uv_sphere()
    t = tracker.Tracker(rest, tris, np.full(len(rest), 0.5, np.float32))
    # Rotations that would slide every vertex around z; mask 0 keeps the tangential moves off.
    rotations = turns_about_z(len(rest))
    still, _ = t.track(ball(1.0), rest, rotations=rotations, mask=np.zeros(len(rest)))
    assert np.abs(still - rest).max() < 1e-4  # on the iso-surface already, nothing to do
    moved, _ = t.track(ball(1.0), rest, rotations=rotations)  # no mask this call: they slide round z
    assert np.abs(moved - rest).max() > 1e-2
    with pytest.raises(isokit.InputError, match="argument 'mask'"):
        t.track(ball(1.0), rest, mask=np.zeros(3))
    with pytest.raises(isokit.InputError):
        t.track(ball(1.0), rest, mask=np.full(len(rest), 2.0))


def test_anchors_pull_vertices_and_pin_them_at_stiffness_one():
    rest, tris = uv_sphere()
    t = tracker.Tracker(rest, tris, np.full(len(rest), 0.5, np.float32))
    rotations = turns_about_z(len(rest))
    free, _ = t.track(ball(1.0), rest, rotations=rotations)
    # Pinned (stiffness 1) at anchors that are the rest positions: the top cap stays exactly put
    # while the rest slides round z.
    cap = rest[:, 2] > 0.5
    k = np.where(cap, 1.0, 0.0)
    held, _ = t.track(ball(1.0), rest, rotations=rotations, stiffness=k, anchors=rest)
    assert np.array_equal(held[cap], rest[cap])
    assert np.abs(held[~cap] - rest[~cap]).max() > 1e-3
    # A pull between: closer to the anchors than free, farther than pinned.
    half, _ = t.track(ball(1.0), rest, rotations=rotations, stiffness=np.full(len(rest), 0.7))
    d_free, d_half = np.abs(free - rest).max(), np.abs(half - rest).max()
    assert 0 < d_half < d_free
    with pytest.raises(isokit.InputError, match="anchors"):
        t.track(ball(1.0), rest, anchors=rest)
    with pytest.raises(isokit.InputError, match="anchor stiffness vertex 0"):
        t.track(ball(1.0), rest, stiffness=np.full(len(rest), 1.5))
