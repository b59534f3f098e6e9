#!/usr/bin/env python3
"""Checks that two builds of isokit behave identically (a refactoring's acceptance test).

Runs `isokit-skin demo` and a bake of the procedural humanoid with each build's `isokit-skin`,
then compares the outputs: the metrics JSON must be equal except the timing fields, and the
baked .glb files byte for byte.

  scripts/same-behaviour.py OLD_BUILD NEW_BUILD [--out DIR] [--quick] [--allow-added-fields]

OLD_BUILD / NEW_BUILD are CMake build folders (holding apps/skinning/isokit-skin). --quick runs a
4,000-vertex humanoid with 9 frames (a minute) instead of the README demo (13k, 31 frames).
--allow-added-fields accepts metrics fields that only the new build writes (a new metric), listing
them. The demo writes the default method's .glb: the .glb files both demos wrote are compared (none
when the default method changed between the builds; the bake's .glb is compared in any case).
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
TIMING = {"mean_ms", "ms", "ratio_to_dqs", "vertex_iterations_per_second", "fit_seconds", "setup_seconds"}


def strip_timing(node):
    if isinstance(node, dict):
        return {k: strip_timing(v) for k, v in node.items() if k not in TIMING}
    if isinstance(node, list):
        return [strip_timing(v) for v in node]
    return node


def differences(a, b, path="$", added=None):
    """Paths where two JSON values differ (NaN equals NaN). With `added` (a set), keys only in `b`
    are collected there instead of counted as differences."""
    if isinstance(a, dict) and isinstance(b, dict):
        only_new = set(b) - set(a) if added is not None else set()
        if added is not None:
            added.update(f"{path}.{k}" for k in only_new)
        out = [f"{path}.{k}: only in one file" for k in sorted((set(a) ^ set(b)) - only_new)]
        for k in sorted(set(a) & set(b)):
            out += differences(a[k], b[k], f"{path}.{k}", added)
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{path}: {len(a)} vs {len(b)} entries"]
        out = []
        for i, (x, y) in enumerate(zip(a, b)):
            out += differences(x, y, f"{path}[{i}]", added)
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
    return {"demo": (demo, "metrics.json", None), "bake": (bake, "metrics.json", "bake.glb")}


def same_glbs(old_dir, new_dir, glb):
    """(compared names, names that differ): `glb`, or every .glb both folders hold."""
    names = [glb] if glb else sorted(set(f for f in os.listdir(old_dir) if f.endswith(".glb")) &
                                     set(f for f in os.listdir(new_dir) if f.endswith(".glb")))
    differ = [n for n in names
              if not filecmp.cmp(os.path.join(old_dir, n), os.path.join(new_dir, n), shallow=False)]
    return names, differ


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--out", default="out/same-behaviour")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--allow-added-fields", action="store_true")
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
        added = set() if a.allow_added_fields else None
        diff = differences(old, new, added=added)
        problems += [f"{name}: metrics {d}" for d in diff[:20]]
        names, differ = same_glbs(outs["old"], outs["new"], glb)
        problems += [f"{name}: {n} differs" for n in differ]
        fields = sorted({p.split(".")[-1] for p in added or ()})
        print(f"same-behaviour: {name}: metrics {'identical' if not diff else f'{len(diff)} differences'}"
              f" (timing fields aside{'; fields added: ' + ', '.join(fields) if fields else ''}), "
              f"{', '.join(names) or 'no .glb in common'} {'identical' if not differ else 'differ'}")
    for p in problems:
        print("  " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
