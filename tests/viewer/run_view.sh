#!/bin/sh
# The viewer's `gui` test: isokit-skin view under Xvfb (Mesa software GL) replays
# tests/viewer/view_drag.json — a click on a joint in the view, a drag of its x slider to 145°, the
# DQS method with the self-intersection overlay, a missing file and then the procedural finger
# opened — then checks the report: the joint is selected and highlighted, the slider turned it, the
# mesh moved, the overlays show DQS's self-intersections and folds, the missing file's error is
# shown, the finger replaces the cylinder. The screenshot folder does not exist beforehand: the
# viewer creates it.
# Exits 77 (CTest: skipped) without xvfb-run. With ISOKIT_UPDATE_DOC_IMAGES=1 the screenshots go
# to docs/figures/ (the pictures of docs/skinning.md, "The viewer").
# Usage: run_view.sh EXE SCRIPT OUT DOC_IMAGES
set -u
exe=$1 script=$2 out=$3 doc_images=$4
if ! command -v xvfb-run >/dev/null 2>&1; then
  echo "SKIPPED: xvfb-run not found (apt-get install xvfb xauth libgl1-mesa-dri)"
  exit 77
fi
rm -rf "$out" && mkdir -p "$out" || exit 1
LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" \
  "$exe" view procedural:cylinder --script "$script" --screenshot-dir "$out/shots" || { echo "isokit-skin view failed"; exit 1; }
python3 - "$out/shots/viewer-report.json" <<'PY' || exit 1
import json, os, sys
r = json.load(open(sys.argv[1]))
shots = {s["name"]: s for s in r["screenshots"]}
checks = [
    (r["script_failures"] == [], "the script ran without failures"),
    (all(os.path.getsize(s["file"]) > 10000 for s in shots.values()), "every screenshot was written"),
    (shots["view-rest"]["joint_pixels"] > 20, "the rest view shows the skeleton (not blank)"),
    (shots["view-bent"]["selected"] == "Bone1", "a click on the joint in the view selected it"),
    (shots["view-bent"]["selected_pixels"] > 20, "the selected joint is highlighted"),
    (shots["view-bent"]["angles"][0] > 100, "dragging the x slider turned the joint"),
    (abs(shots["view-bent"]["positions_sum"] - shots["view-rest"]["positions_sum"]) > 1, "the mesh moved"),
    (shots["view-dqs-intersections"]["method"] == "dqs", "the method switched to dqs"),
    (shots["view-dqs-intersections"]["overlay_pixels"] > 50, "the overlay shows DQS's self-intersections"),
    (shots["view-dqs-folds"]["overlay"] == "folds" and shots["view-dqs-folds"]["folded_triangles"] > 0,
     "the folds overlay is on and flags DQS's folded triangles (inside the crease)"),
    ("nonexistent" in shots["view-open-error"]["message"] and shots["view-open-error"]["joints"] == 2,
     "opening a missing file shows its error and keeps the rig"),
    (shots["view-opened"]["joints"] == 4 and shots["view-opened"]["joint_pixels"] > 20,
     "opening another rig (the procedural finger) shows it"),
]
for ok, what in checks:
    print(("ok  : " if ok else "FAIL: ") + what)
sys.exit(0 if all(ok for ok, _ in checks) else 1)
PY
if [ "${ISOKIT_UPDATE_DOC_IMAGES:-0}" = 1 ]; then
  for name in view-bent view-dqs-intersections; do cp "$out/shots/$name.png" "$doc_images/$name.png" || exit 1; done
  echo "copied the screenshots to $doc_images"
fi
