# SPDX-License-Identifier: MIT
"""isokit.operators from Python: specs, generation, evaluation, controllers, checks, files."""
import json
import math
import threading

import numpy as np
import pytest

import isokit
from isokit import operators as ops


def small_spec(name="contact", resolution=16):
    spec = ops.preset_spec(name, resolution)
    spec["slices"] = 8
    return spec


def test_module_basics():
    assert isokit.__version__.count(".") == 2
    assert issubclass(isokit.InputError, ValueError)
    assert "contact" in ops.presets()
    import isokit.operators as again  # the submodule imports by name too

    assert again is ops


def test_threads_setting_round_trips():
    before = isokit.get_num_threads()
    isokit.set_num_threads(1)
    assert isokit.get_num_threads() == 1
    isokit.set_num_threads(0)
    assert isokit.get_num_threads() == before
    with pytest.raises(isokit.InputError, match="argument 'n'"):
        isokit.set_num_threads(-1)


def test_generate_meets_the_boundary_conditions_and_the_checks():
    spec = small_spec()
    grid = ops.generate(spec)
    assert grid.dtype == np.float32 and grid.shape == (8, 16, 16)
    # 2014 eq. 1: g(f1, 0) = f1 and g(0, f2) = f2 on the axes of every slice.
    h = np.linspace(0, 1, 16, dtype=np.float32)
    assert np.abs(grid[:, :, 0] - h).max() < 1e-5
    assert np.abs(grid[:, 0, :] - h).max() < 1e-5
    report = ops.inspect(spec, grid)
    assert report["failure"] is None
    assert len(report["slices"]) == 8
    assert all(s["boundary_error"] <= 1e-5 for s in report["slices"])


def test_generate_takes_a_json_path_and_reports_progress(tmp_path):
    spec = small_spec()
    path = tmp_path / "spec.json"
    path.write_text(json.dumps(spec))
    seen = []
    grid = ops.generate(path, progress=lambda done, total: seen.append((done, total)))
    assert np.array_equal(grid, ops.generate(spec))
    assert seen and seen[-1] == (8, 8) and sorted(seen) == seen


def test_an_exception_in_the_progress_callback_stops_the_work():
    def stop(done, total):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        ops.generate(small_spec(), progress=stop)


def test_evaluate_matches_the_grid_at_nodes_and_its_derivatives_match_finite_differences():
    grid = ops.generate(small_spec())
    rng = np.random.default_rng(3)
    # At nodes: the stored values.
    i1, i2 = np.meshgrid(np.arange(16), np.arange(16), indexing="ij")
    g, _, _ = ops.evaluate(grid, i1 / 15.0, i2 / 15.0, 0.0)
    assert np.abs(g - grid[0]).max() < 1e-5
    # Derivatives against central differences inside the square.
    f1 = rng.uniform(0.1, 0.9, 200).astype(np.float32)
    f2 = rng.uniform(0.1, 0.9, 200).astype(np.float32)
    d = rng.uniform(0, 1, 200).astype(np.float32)
    g, g1, g2 = ops.evaluate(grid, f1, f2, d)
    e = np.float32(1e-3)
    n1 = (ops.evaluate(grid, f1 + e, f2, d)[0] - ops.evaluate(grid, f1 - e, f2, d)[0]) / (2 * e)
    n2 = (ops.evaluate(grid, f1, f2 + e, d)[0] - ops.evaluate(grid, f1, f2 - e, d)[0]) / (2 * e)
    assert np.abs(g1 - n1).max() < 2e-2
    assert np.abs(g2 - n2).max() < 2e-2


def test_evaluate_accepts_any_real_dtype_and_broadcasts():
    grid = ops.generate(small_spec())
    f = np.linspace(0, 1, 7)
    ref = ops.evaluate(grid, f.astype(np.float32), f.astype(np.float32), np.zeros(7, np.float32))[0]
    for dtype in (np.float64, np.float16, np.int32):
        x = (f * 4).astype(dtype) / 4 if dtype != np.int32 else (f > 0.5).astype(dtype)
        g = ops.evaluate(grid, x, x, 0)[0]
        assert g.shape == (7,) and g.dtype == np.float32
    assert np.allclose(ops.evaluate(grid, f, f, 0)[0], ref)
    g = ops.evaluate(grid, f[:, None], f[None, :], 0.5)[0]
    assert g.shape == (7, 7)


def test_bad_arguments_give_one_line_errors_naming_them():
    grid = ops.generate(small_spec())
    with pytest.raises(isokit.InputError, match="argument 'f1': expected real numbers") as e:
        ops.evaluate(grid, np.array(["a", "b"]), [0.1, 0.2], 0)
    assert "\n" not in str(e.value)
    with pytest.raises(isokit.InputError, match="argument 'grid': expected shape"):
        ops.evaluate(np.zeros((4, 4)), 0.1, 0.1, 0)
    with pytest.raises(isokit.InputError, match="do not broadcast"):
        ops.evaluate(grid, np.zeros(3), np.zeros(4), 0)
    with pytest.raises(isokit.InputError, match="argument 'spec'"):
        ops.generate(42)
    bad = small_spec()
    bad["resolution"] = 4
    with pytest.raises(isokit.InputError, match="resolution"):
        ops.generate(bad)
    with pytest.raises(isokit.InputError, match="argument 'backend'"):
        ops.generate(small_spec(), backend="magic")


def test_controllers_presets_and_custom_knots():
    c = ops.Controller.preset("contact")
    assert c.name == "contact" and c.knots.shape[1] == 2
    d = c(np.array([0.0, math.pi / 4, math.pi]))
    assert d[0] == 0 and d[1] == 0 and d[2] == pytest.approx(1)
    ramp = ops.Controller([[0, 0], [math.pi, 1]], "ramp")
    alpha = np.linspace(0, math.pi, 11)
    values = ramp(alpha)
    assert np.all(np.diff(values) >= 0) and values[-1] == pytest.approx(1)
    with pytest.raises(isokit.InputError):
        ops.Controller([[0.5, 0], [math.pi, 1]])  # must start at 0
    with pytest.raises(isokit.InputError, match="argument 'knots'"):
        ops.Controller([[0, 0, 0]])


def test_save_and_load_round_trip(tmp_path):
    spec = small_spec()
    grid = ops.generate(spec)
    ops.save(tmp_path / "op.npy", spec, grid)
    spec_back, grid_back = ops.load(tmp_path / "op.npy")
    assert np.array_equal(grid_back, grid)
    assert spec_back["resolution"] == 16 and spec_back["slices"] == 8
    assert np.array_equal(np.load(tmp_path / "op.npy"), grid)  # a plain .npy for NumPy


def test_generate_releases_the_gil():
    # A thread records when it runs; generate() holds no GIL if that thread runs during a call.
    # A loaded machine may not schedule it during one call, so up to 20 calls are made: with the
    # GIL held, a call could see at most the ticks of its entry and its exit (two switches).
    import time

    spec = small_spec(resolution=64)
    ticks = []
    started, done = threading.Event(), threading.Event()

    def count():
        started.set()
        while not done.is_set():
            ticks.append(time.monotonic())
            done.wait(0.001)

    t = threading.Thread(target=count)
    t.start()
    started.wait()
    inside = 0
    for _ in range(20):
        t0 = time.monotonic()
        ops.generate(spec)
        t1 = time.monotonic()
        inside = max(inside, sum(1 for x in list(ticks) if t0 < x < t1))
        if inside >= 3:
            break
    done.set()
    t.join()
    assert inside >= 3


def test_ctrl_c_interrupts_a_long_call():
    import os
    import signal

    def press_ctrl_c(done, total):
        if done == 1:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        ops.generate(small_spec(resolution=32), progress=press_ctrl_c)
    # The module still works afterwards.
    assert ops.generate(small_spec()).shape == (8, 16, 16)
