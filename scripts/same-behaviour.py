#!/usr/bin/env python3
"""Checks that two builds of isokit behave identically (a refactoring's acceptance test).

Runs `isokit-skin demo` and a bake of the procedural humanoid with each build's `isokit-skin`,
then compares the outputs: the metrics JSON must be equal except the timing fields, and the
baked .glb files byte for byte.

  scripts/same-behaviour.py OLD_BUILD NEW_BUILD [--out DIR] [--quick]

OLD_BUILD / NEW_BUILD are CMake build folders (holding apps/skinning/isokit-skin). --quick runs a
4,000-vertex humanoid with 9 frames (a minute) instead of the README demo (13k, 31 frames).
Exit 0 when everything is identical; 1 with the differences listed otherwise.
"""
import argparse
import filecmp
import json
import math
import os
import subprocess
import sys

# Fields that measure time, not behaviour.
TIMING = {"mean_ms", "ms", "ratio_to_dqs", "vertex_iterations_per_second", "fit_seconds"}


def strip_timing(node):
    if isinstance(node, dict):
        return {k: strip_timing(v) for k, v in node.items() if k not in TIMING}
    if isinstance(node, list):
        return [strip_timing(v) for v in node]
    return node


def differences(a, b, path="$"):
    """Paths where two JSON values differ (NaN equals NaN)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{path}.{k}: only in one file" for k in sorted(set(a) ^ set(b))]
        for k in sorted(set(a) & set(b)):
            out += differences(a[k], b[k], f"{path}.{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} entries"]
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += differences(x, y, f"{path}[{i}]")
        return out
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return []
    return [] if a == b else [f"{path}: {a!r} vs {b!r}"]


def run(exe, args, log):
    with open(log, "w") as f:
        rc = subprocess.call([exe] + args, stdout=f, stderr=subprocess.STDOUT)
    if rc != 0:
        sys.exit(f"same-behaviour: {exe} {' '.join(args)} failed with {rc} (log: {log})")


def cases(quick):
    vertices = 4000 if quick else 13000
    frames = 9 if quick else 31
    demo = ["demo", "--vertices", str(vertices), "--frames", str(frames)]
    bake = ["bake", f"procedural:humanoid?vertices={vertices}", "--method", "tracking2014",
            "--bend", "RightForeArm:x:120", "--bend", "RightLeg:x:120", "--frames", str(frames),
            "--compare", "--no-self-intersections"]
    return {"demo": (demo, "metrics.json", "tracking2014.glb"), "bake": (bake, "metrics.json", "bake.glb")}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--out", default="out/same-behaviour")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args()
    problems = []
    for name, (args, metrics, glb) in cases(a.quick).items():
        outs = {}
        for side, build in (("old", a.old), ("new", a.new)):
            exe = os.path.join(build, "apps", "skinning", "isokit-skin")
            d = os.path.join(a.out, side, name)
            os.makedirs(d, exist_ok=True)
            extra = ["--out", d] if name == "demo" else \
                ["--out", os.path.join(d, glb), "--metrics", os.path.join(d, metrics)]
            print(f"same-behaviour: {side} {name}", flush=True)
            run(exe, args + extra, os.path.join(d, "log.txt"))
            outs[side] = d
        with open(os.path.join(outs["old"], metrics)) as f:
            old = strip_timing(json.load(f))
        with open(os.path.join(outs["new"], metrics)) as f:
            new = strip_timing(json.load(f))
        diff = differences(old, new)
        problems += [f"{name}: metrics {d}" for d in diff[:20]]
        if not filecmp.cmp(os.path.join(outs["old"], glb), os.path.join(outs["new"], glb), shallow=False):
            problems.append(f"{name}: {glb} differs")
        print(f"same-behaviour: {name}: metrics {'identical' if not diff else f'{len(diff)} differences'}"
              f" (timing fields aside), {glb} "
              f"{'identical' if not problems or not problems[-1].endswith('differs') else 'differs'}")
    for p in problems:
        print("  " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
