#!/usr/bin/env python3
"""Benchmark of the design studio's window (`make bench-studio`, docs/performance.md).

  bench/studio/studio-bench.py BUILD [--runs 5] [--out DIR] [--script bench/studio/drag.json]

Replays a recorded drag (bench/studio/drag.json: the contact line's end of g_dc at d = 0.7 dragged
round a small loop, one mouse move per frame, 160 frames) in a 1280x800 window of
`isokit-opdesigner gui` (128² x 128 operator) under Xvfb with Mesa software GL, redrawing every
frame, `--runs` times; then runs BM_EditSlice (bench_operators) in the same session. Prints, per
quantity, the median over the runs' medians and the spread (min..max of the run medians):
- re-solve of the displayed slice (StudioModel::last_solve_ms after each accepted drag step),
  target <= 10 ms, next to BM_EditSlice/3 (the same solve without the window and the background);
- latency: frames from a drag input to the redrawn slice, the input frame counting as 1, target <= 2;
- frames per second during the drag (1000 / median frame time of the drag frames), target >= 30.
Writes DIR/studio-bench.json. Exit 77 without xvfb-run.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys


def run_gui(build, script, out_dir, i):
    report = os.path.join(out_dir, f"run{i}.json")
    env = dict(os.environ, LIBGL_ALWAYS_SOFTWARE="1")
    cmd = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24",
           os.path.join(build, "apps", "opdesigner", "isokit-opdesigner"), "gui", "--size", "1280x800",
           "--script", script, "--screenshot-dir", out_dir, "--report", report, "--recent-files", ""]
    subprocess.run(cmd, check=True, env=env)
    with open(report) as f:
        return json.load(f)


def edit_slice(build, out_dir):
    out = os.path.join(out_dir, "edit_slice.json")
    subprocess.run([os.path.join(build, "bench", "bench_operators"), "--benchmark_filter=^BM_EditSlice/",
                    "--benchmark_repetitions=5", "--benchmark_out=" + out, "--benchmark_out_format=json"],
                   check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        data = json.load(f)
    times = {}
    for b in data["benchmarks"]:
        if b.get("run_type") == "iteration":
            times.setdefault(b["run_name"], []).append(b["real_time"])  # ms (Unit(kMillisecond))
    return times, data.get("context", {})


def summary(values):
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--out", default=None)
    ap.add_argument("--script", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "drag.json"))
    a = ap.parse_args()
    if shutil.which("xvfb-run") is None:
        print("studio-bench: xvfb-run not found (apt-get install xvfb xauth libgl1-mesa-dri)")
        return 77
    out_dir = a.out or os.path.join(a.build, "bench-results", "studio")
    os.makedirs(out_dir, exist_ok=True)
    runs = [run_gui(a.build, a.script, out_dir, i) for i in range(a.runs)]
    edit, context = edit_slice(a.build, out_dir)
    rows = {
        "re-solve of the displayed slice (ms)": [r["timing"]["solve_ms"]["median"] for r in runs],
        "  p90 within a run (ms)": [r["timing"]["solve_ms"]["p90"] for r in runs],
        "latency, input to redrawn slice (frames), median": [r["timing"]["latency_frames"]["median"] for r in runs],
        "latency, max": [r["timing"]["latency_frames"]["max"] for r in runs],
        "frames per second during the drag": [r["drag"]["fps"] for r in runs],
        "frame time during the drag (ms)": [r["drag"]["frame_ms_median"] for r in runs],
        "  of which widgets + model (ms)": [r["drag_ui"]["frame_ms_median"] for r in runs],
    }
    for name, times in sorted(edit.items()):
        rows[name + " (ms)"] = times
    result = {"runs": a.runs, "gl_renderer": runs[0].get("gl_renderer"), "window": runs[0].get("window"),
              "resolution": runs[0].get("resolution"), "nproc": os.cpu_count(), "context": context,
              "rows": {k: summary(v) for k, v in rows.items()}}
    print(f"studio drag, {a.runs} runs, {result['window']} window, {result['resolution']}² operator, "
          f"{result['gl_renderer']}, nproc {os.cpu_count()}")
    print(f"{'quantity':<52} {'median':>9} {'spread':>21}")
    for k, s in result["rows"].items():
        print(f"{k:<52} {s['median']:9.2f} {s['min']:9.2f} .. {s['max']:9.2f}")
    with open(os.path.join(out_dir, "studio-bench.json"), "w") as f:
        json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
