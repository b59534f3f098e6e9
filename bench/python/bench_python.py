#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""The Python module's overhead (docs/performance.md, "Python"): in one run,

- evaluating a field on 1 M float32 C-contiguous points from Python (`field.evaluate`) against
  the C++ call it wraps (`Field::eval_batch`, timed inside the module), for a sphere, an HRBF and
  a composition of two capsules by the contact operator; best of 5 each;
- a field written in NumPy in the tracker: seconds per tracker iteration in the Python field and
  in the rest of the tracker, against the same ball as an isokit field.

Usage: PYTHONPATH=build/python python3 bench/python/bench_python.py
"""
import time

import numpy as np

import isokit
from isokit import fields, operators as ops, tracker


def best(f, repeats=5):
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def eval_rows(n=1_000_000):
    rng = np.random.default_rng(0)
    u = rng.normal(size=(60, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    spec = ops.preset_spec("contact", 64)
    spec["slices"] = 16
    c, s = np.cos(1.0), np.sin(1.0)
    arm = fields.capsule([0, 0, 0], [1, 0, 0], 0.25)
    forearm = fields.capsule([0, 0, 0], [1, 0, 0], 0.22).transformed([[c, -s, 0], [s, c, 0], [0, 0, 1]], [1, 0, 0])
    cases = {
        "sphere": fields.sphere([0, 0, 0], 1.0),
        "HRBF (60 samples)": fields.fit_hrbf(u, u, r=0.5),
        "two capsules, contact operator": fields.compose(arm, forearm, ops.generate(spec), "contact"),
    }
    rows = []
    for name, f in cases.items():
        lo, hi = (np.array(x) for x in f.support)
        points = rng.uniform(lo, hi, size=(n, 3)).astype(np.float32)
        f.evaluate(points)  # warm up (first-use compilation, page faults)
        py = best(lambda: f.evaluate(points))
        cpp = f._cpp_eval_seconds(points, 5)
        rows.append((name, cpp * 1e3, py * 1e3, py / cpp))
    return rows


def uv_sphere(rings, segments):
    t, p = np.meshgrid(np.linspace(0, np.pi, rings + 2)[1:-1], np.linspace(0, 2 * np.pi, segments, endpoint=False),
                       indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    rest = np.vstack([[0, 0, 1], ring, [0, 0, -1]]).astype(np.float32)
    bottom, last = len(rest) - 1, 1 + (rings - 1) * segments
    tris = []
    for j in range(segments):
        j1 = (j + 1) % segments
        tris += [[0, 1 + j, 1 + j1], [bottom, last + j1, last + j]]
        for i in range(rings - 1):
            a, b = 1 + i * segments, 1 + (i + 1) * segments
            tris += [[a + j, b + j, b + j1], [a + j, b + j1, a + j1]]
    return rest, np.array(tris)


def ball(radius, width=0.5):
    def f(p):
        r = np.linalg.norm(p, axis=1)
        v = np.clip(0.5 + (radius - r) / (2 * width), 0, 1)
        g = -p / (2 * width * np.maximum(r, 1e-9)[:, None])
        g[(v <= 0) | (v >= 1)] = 0
        return v.astype(np.float32), g.astype(np.float32)

    return f


def tracker_rows():
    rest, tris = uv_sphere(100, 100)  # 10,002 vertices
    iso = np.full(len(rest), 0.5, np.float32)
    rows = []
    for name, field in (("ball in NumPy (Python callable)", ball(1.2)),
                        ("ball as an isokit field", fields.sphere([0, 0, 0], 1.2, 0.5))):
        t = tracker.Tracker(rest, tris, iso, max_iterations=30)
        t0 = time.perf_counter()
        _, stats = t.track(field, rest)
        wall = time.perf_counter() - t0
        it = max(stats["iterations"], 1)
        rows.append((name, len(rest), stats["iterations"], wall / it * 1e3, stats["python_field_seconds"] / it * 1e3,
                     stats["python_field_calls"] / it))
    return rows


def main():
    print(f"isokit {isokit.__version__}, {isokit.get_num_threads()} threads, NumPy {np.__version__}")
    print()
    print("| field (1 M float32 points) | C++ eval_batch ms | Python evaluate ms | ratio |")
    print("|---|---:|---:|---:|")
    for name, cpp, py, ratio in eval_rows():
        print(f"| {name} | {cpp:.1f} | {py:.1f} | {ratio:.3f} |")
    print()
    print("| tracked field | vertices | iterations | ms / iteration | of which in the Python field | field calls / iteration |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, v, it, ms, py_ms, calls in tracker_rows():
        print(f"| {name} | {v} | {it} | {ms:.2f} | {py_ms:.2f} | {calls:.2f} |")


if __name__ == "__main__":
    main()
