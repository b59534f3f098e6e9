#!/bin/sh
# The newcomer test: follows the README's "Your own character" commands with the built
# isokit-skin on a character the project writes itself (the procedural cylinder with a clip,
# saved as .glb through the Python module), and on the shared rig CesiumMan when ISOKIT_SHARED_DATA
# names the shared data folder; checks that each command's outputs exist. The `view` step runs the
# window under Xvfb with a short script (skipped without xvfb-run or a GUI build).
# Exits 77 (CTest: skipped) without the Python module.
# Usage: run_readme.sh ISOKIT_SKIN PYTHONPATH OUT
set -u
exe=$1 pypath=$2 out=$3
rm -rf "$out" && mkdir -p "$out" || exit 1
PYTHONPATH="$pypath" /usr/bin/python3 - "$out/my_character.glb" <<'PY' || { echo "SKIPPED: no Python module"; exit 77; }
import sys
import numpy as np
from isokit import skinning
rig = skinning.load("procedural:cylinder")
rest = rig.rest_pose()
poses = np.repeat(rest[None], 12, axis=0)
for f in range(12):
    a = np.radians(90) * f / 11
    r = np.eye(4)
    r[1:3, 1:3] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    poses[f, 1] = rest[1] @ r
rig.add_clip("Walk", poses)
rig.save(sys.argv[1])
PY
fail=0
check() { if [ -s "$1" ]; then echo "ok  : $2"; else echo "FAIL: $2 ($1 missing or empty)"; fail=1; fi; }
run_readme() {  # CHARACTER CLIP TAG
  "$exe" info "$1" > "$out/$3-info.txt" 2>&1 || { echo "FAIL: info $1"; fail=1; }
  grep -q "^joints:" "$out/$3-info.txt" && echo "ok  : info $3 lists the joints" || { echo "FAIL: info $3"; fail=1; }
  "$exe" bake "$1" --clip "$2" --out "$out/$3-walk.glb" --pc2 "$out/$3-walk.pc2" > "$out/$3-bake.txt" 2>&1 ||
    { echo "FAIL: bake $1 (see $out/$3-bake.txt)"; fail=1; }
  check "$out/$3-walk.glb" "bake $3 wrote the .glb"
  check "$out/$3-walk.pc2" "bake $3 wrote the point cache"
  if command -v xvfb-run >/dev/null 2>&1 && "$exe" view --help >/dev/null 2>&1; then
    printf '{"events": [{"type": "wait_baked"}, {"type": "frames", "n": 2}, {"type": "screenshot", "name": "%s-view"}]}\n' "$3" > "$out/$3-view.json"
    LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" "$exe" view "$1" --clip "$2" \
      --script "$out/$3-view.json" --screenshot-dir "$out" --report "$out/$3-view-report.json" > "$out/$3-view.txt" 2>&1 ||
      { echo "FAIL: view $1 (see $out/$3-view.txt)"; fail=1; }
    check "$out/$3-view.png" "view $3 opened the window and took its picture"
  else
    echo "skip: view (no xvfb-run or no GUI build)"
  fi
}
run_readme "$out/my_character.glb" Walk cylinder
if [ -n "${ISOKIT_SHARED_DATA:-}" ] && [ -f "$ISOKIT_SHARED_DATA/rigs/CesiumMan.glb" ]; then
  run_readme "$ISOKIT_SHARED_DATA/rigs/CesiumMan.glb" animation_0 cesiumman
fi
exit $fail
