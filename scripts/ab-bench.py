#!/usr/bin/env python3
"""A/B benchmark of two builds, alternated in one run (docs/performance.md protocol).

  scripts/ab-bench.py OLD_BUILD NEW_BUILD [--rounds 3] [--min-time S] [--case PROGRAM:FILTER ...]

For each round and each case, runs OLD_BUILD/bench/PROGRAM then NEW_BUILD/bench/PROGRAM with
`--benchmark_filter=FILTER` (one repetition each, so that the two builds alternate and share the
machine's drift), and prints per benchmark the median time of each build over the rounds and the
median of the per-round ratios new / old. Exit 1 when a ratio leaves [--low, --high].
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

DEFAULT_CASES = [
    "bench_implicit:^BM_TreeEval/",
    "bench_track:^BM_TrackIterations/",
    "bench_skinning:^BM_SkinStep/3/13000/50/",
]
UNIT = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}


def run(build, program, pattern, min_time):
    exe = os.path.join(build, "bench", program)
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        out = f.name
    subprocess.run([exe, f"--benchmark_filter={pattern}", f"--benchmark_out={out}",
                    "--benchmark_out_format=json"] + ([f"--benchmark_min_time={min_time}"] if min_time else []), check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        data = json.load(f)
    os.unlink(out)
    times = {}
    for b in data["benchmarks"]:
        if b.get("run_type", "iteration") != "iteration":
            continue
        times[b["name"]] = b["real_time"] * UNIT[b["time_unit"]]
    return times


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--case", action="append", dest="cases")
    ap.add_argument("--min-time", type=float, default=0,
                    help="--benchmark_min_time per benchmark, seconds (benchmarks with fixed iterations ignore it)")
    ap.add_argument("--low", type=float, default=0.95)
    ap.add_argument("--high", type=float, default=1.05)
    a = ap.parse_args()
    cases = a.cases or DEFAULT_CASES
    old, new = {}, {}
    for r in range(a.rounds):
        for case in cases:
            program, pattern = case.split(":", 1)
            print(f"ab-bench: round {r + 1}/{a.rounds} {program} {pattern}", file=sys.stderr, flush=True)
            for name, t in run(a.old, program, pattern, a.min_time).items():
                old.setdefault(name, []).append(t)
            for name, t in run(a.new, program, pattern, a.min_time).items():
                new.setdefault(name, []).append(t)
    print("| benchmark | old ms (median) | new ms (median) | new / old (median of rounds) | rounds |")
    print("|---|---:|---:|---:|---:|")
    bad = 0
    for name in old:
        if name not in new:
            continue
        ratios = [n / o for o, n in zip(old[name], new[name]) if o > 0]
        ratio = statistics.median(ratios)
        bad += not (a.low <= ratio <= a.high)
        print(f"| {name} | {statistics.median(old[name]):.3f} | {statistics.median(new[name]):.3f} | "
              f"{ratio:.3f} | {len(ratios)} |")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
