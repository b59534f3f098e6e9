#!/bin/sh
# The viewer's drag benchmark (docs/performance.md, "The skinning viewer"): under Xvfb, RUNS times,
# the window (1280x800) opens RIG (default ../shared/data/rigs/CesiumMan.glb), a click picks the
# left elbow and its z slider is dragged from 0 to 90 degrees over 90 frames with tracking2014
# (bench/viewer/drag_elbow.json). A/B in each run: the edited pose tracked whole and shown when
# done ("whole": --edit-slice-ms 0 --skin-wait-ms 0) and the defaults (shown after a first part of
# the solve, each frame waiting a few ms for it). Prints per run and setting the drag's redraw
# rate (fps, from the median frame time), the lag in frames of the skin shown behind the slider
# (largest, and drag frames over 2) and the median deformation time of a shown frame.
# Usage: view-bench.sh BUILD_DIR [RUNS] [RIG]
set -eu
build=$1 runs=${2:-3} rig=${3:-../shared/data/rigs/CesiumMan.glb}
here=$(dirname "$0")
out=$(mktemp -d)
echo "| run | setting | drag fps | frame ms (median) | lag frames (max) | frames lagging > 2 | bake ms (median) |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for k in $(seq 1 "$runs"); do
  for setting in whole default; do
    arg=""
    [ "$setting" = default ] || arg="--edit-slice-ms 0 --skin-wait-ms 0"
    # shellcheck disable=SC2086
    LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" "$build/apps/skinning/isokit-skin" view "$rig" \
      --script "$here/drag_elbow.json" --screenshot-dir "$out" $arg >/dev/null 2>&1
    python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))['drag']
late = sum(1 for x in d['lag_frames'] if x > 2)
print('| %s | %s | %.1f | %.1f | %d | %d | %.1f |' % (sys.argv[2], sys.argv[3], d['fps'], d['frame_ms_median'],
      d['lag_frames_max'], late, d['bake_ms_median']))" "$out/viewer-report.json" "$k" "$setting"
  done
done
rm -rf "$out"
