#!/bin/sh
# The viewer's drag benchmark (docs/performance.md, "The viewer"): under Xvfb, RUNS times, the
# window (1280x800) opens RIG (default ../shared/data/rigs/CesiumMan.glb), a click picks the left
# elbow and its z slider is dragged from 0 to 90 degrees over 90 frames with tracking2014
# (bench/viewer/drag_elbow.json); prints per run the drag's redraw rate (fps, from the median frame
# time) and the largest lag in frames of the skin shown behind the slider.
# Usage: view-bench.sh BUILD_DIR [RUNS] [RIG]
set -eu
build=$1 runs=${2:-3} rig=${3:-../shared/data/rigs/CesiumMan.glb}
here=$(dirname "$0")
out=$(mktemp -d)
echo "| run | drag fps | frame ms (median) | lag frames (max) | bake ms (median) |"
echo "|---|---:|---:|---:|---:|"
for k in $(seq 1 "$runs"); do
  LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" "$build/apps/skinning/isokit-skin" view "$rig" \
    --script "$here/drag_elbow.json" --screenshot-dir "$out" >/dev/null 2>&1
  python3 -c "import json,sys; d=json.load(open(sys.argv[1]))['drag']; print('| %s | %.1f | %.1f | %d | %.1f |' % (sys.argv[2], d['fps'], d['frame_ms_median'], d['lag_frames_max'], d['bake_ms_median']))" \
    "$out/viewer-report.json" "$k"
done
rm -rf "$out"
