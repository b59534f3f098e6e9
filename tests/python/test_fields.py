# SPDX-License-Identifier: MIT
"""isokit.fields from Python: primitives, HRBF fits, grids, compositions, transforms."""
import numpy as np
import pytest

import isokit
from isokit import fields, operators as ops


def sphere_points(n, radius=1.0, center=(0, 0, 0), seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return np.asarray(center) + radius * v, v


def central_gradient(field, points, h=1e-3):
    g = np.zeros_like(points)
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        g[:, k] = (field.evaluate(points + e)[0] - field.evaluate(points - e)[0]) / (2 * h)
    return g


def test_sphere_is_half_on_its_surface_one_inside_zero_outside_its_support():
    s = fields.sphere([0, 0, 0], 1.0)
    on, _ = sphere_points(100)
    v, g = s.evaluate(on)
    assert v.dtype == np.float32 and v.shape == (100,) and g.shape == (100, 3)
    assert np.abs(v - 0.5).max() < 1e-5
    assert s.evaluate([[0, 0, 0]])[0][0] == pytest.approx(1)
    lo, hi = s.support
    assert s.evaluate([[hi[0] + 0.1, 0, 0]])[0][0] == 0


@pytest.mark.parametrize(
    "make",
    [
        lambda: fields.sphere([0.1, 0, 0], 0.8),
        lambda: fields.capsule([0, -0.5, 0], [0, 0.5, 0], 0.4),
        lambda: fields.union(fields.sphere([-0.3, 0, 0], 0.5), fields.sphere([0.3, 0, 0], 0.5)),
        lambda: fields.clean_union(fields.sphere([-0.3, 0, 0], 0.5), fields.sphere([0.3, 0, 0], 0.5)),
    ],
)
def test_gradients_match_finite_differences_and_point_inward(make):
    f = make()
    rng = np.random.default_rng(7)
    p = rng.uniform(-0.9, 0.9, size=(300, 3))
    v, g = f.evaluate(p)
    keep = (v > 0.05) & (v < 0.95)  # inside the support, away from the clamps
    assert keep.sum() > 30
    num = central_gradient(f, p[keep])
    assert np.abs(g[keep] - num).max() < 5e-2 * max(1.0, np.abs(num).max())


def test_an_hrbf_fitted_to_a_sphere_reproduces_it():
    points, normals = sphere_points(60, radius=0.7, seed=2)
    f = fields.fit_hrbf(points, normals, r=0.5)
    other, _ = sphere_points(200, radius=0.7, seed=3)
    v, g = f.evaluate(other)
    assert np.abs(v - 0.5).max() < 0.02
    assert f.evaluate([[0, 0, 0]])[0][0] > 0.9
    # gradients point inward
    assert (np.einsum("ij,ij->i", g, other) < 0).all()


def test_a_grid_of_a_field_agrees_with_it():
    s = fields.sphere([0, 0, 0], 0.6)
    grid = s.to_grid(48)
    p = np.random.default_rng(1).uniform(-0.8, 0.8, size=(500, 3))
    assert np.abs(grid.evaluate(p)[0] - s.evaluate(p)[0]).max() < 0.02
    # And from nodes sampled in NumPy.
    n = 33
    axis = np.linspace(-1, 1, n)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    nodes = s.evaluate(np.stack([x, y, z], -1).reshape(-1, 3))[0].reshape(n, n, n)
    g2 = fields.grid(nodes, [-1, -1, -1], [1, 1, 1])
    assert np.abs(g2.evaluate(p)[0] - s.evaluate(p)[0]).max() < 0.03


def test_compositions():
    a = fields.sphere([-0.3, 0, 0], 0.5)
    b = fields.sphere([0.3, 0, 0], 0.5)
    p = np.random.default_rng(4).uniform(-1, 1, size=(400, 3))
    va, vb = a.evaluate(p)[0], b.evaluate(p)[0]
    assert np.abs(fields.union(a, b).evaluate(p)[0] - np.maximum(va, vb)).max() < 1e-6
    # The 2013 gradient blend's and the operators' gradients are the chain rule with d held fixed:
    # d follows the angle between the operands' gradients (2013 §5, 2014 §4), so they are not the
    # exact gradient of the value; only the value is checked here.
    blend = fields.gradient_blend(a, b, "blend2013").evaluate(p)[0]
    assert (blend >= np.maximum(va, vb) - 1e-5).all()  # a blend only adds matter
    spec = ops.preset_spec("contact", 32)
    spec["slices"] = 8
    contact = fields.compose(a, b, ops.generate(spec), controller="contact")
    assert contact.leaf_count == 2 and not contact.is_leaf
    v = contact.evaluate(p)[0]
    assert v.shape == (400,) and np.isfinite(v).all()


def test_a_transformed_field_moves_rigidly():
    s = fields.sphere([0, 0, 0], 0.5)
    c, si = np.cos(0.7), np.sin(0.7)
    rot = np.array([[c, -si, 0], [si, c, 0], [0, 0, 1]])
    t = np.array([1.0, 2.0, 3.0])
    moved = s.transformed(rot, t)
    p = np.random.default_rng(5).uniform(-0.6, 0.6, size=(100, 3))
    v0, g0 = s.evaluate(p)
    v1, g1 = moved.evaluate(p @ rot.T + t)
    assert np.abs(v1 - v0).max() < 1e-5
    assert np.abs(g1 - g0 @ rot.T).max() < 1e-4
    with pytest.raises(isokit.InputError, match="rotation"):
        s.transformed(np.eye(3) * 2, t)


def test_points_of_any_real_dtype_and_bad_shapes():
    s = fields.sphere([0, 0, 0], 1.0)
    ref = s.evaluate(np.zeros((2, 3), np.float32))[0]
    for dtype in (np.float64, np.int64, np.float16, bool):
        assert np.array_equal(s.evaluate(np.zeros((2, 3), dtype))[0], ref)
    with pytest.raises(isokit.InputError, match=r"argument 'points': expected shape \(N, 3\), got \(2, 4\)"):
        s.evaluate(np.zeros((2, 4)))
    with pytest.raises(isokit.InputError, match="argument 'points': expected real numbers"):
        s.evaluate(np.array([["a", "b", "c"]]))
    with pytest.raises(isokit.InputError, match="argument 'radius'"):
        fields.sphere([0, 0, 0], -1)
    with pytest.raises(isokit.InputError, match="argument 'normals'"):
        fields.fit_hrbf(np.zeros((5, 3)), np.zeros((4, 3)))
