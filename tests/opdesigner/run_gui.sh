#!/bin/sh
# The `gui` test: runs isokit-opdesigner gui under Xvfb (Mesa software GL) with a scripted drag
# of a control point, Ctrl+Z and Ctrl+Y, a failed check and a controller knot, then checks the
# report and screenshots (gui_check); then opens a spec given on the command line.
# Exits 77 (CTest: skipped) without xvfb-run. With ISOKIT_UPDATE_DOC_IMAGES=1 the screenshots are
# copied to docs/figures/ (the studio's pictures in docs/operators.md come from this test).
# Usage: run_gui.sh EXE CHECK SCRIPT OUT DOC_IMAGES
set -u
exe=$1 check=$2 script=$3 out=$4 doc_images=$5
if ! command -v xvfb-run >/dev/null 2>&1; then
  echo "SKIPPED: xvfb-run not found (apt-get install xvfb xauth libgl1-mesa-dri)"
  exit 77
fi
rm -rf "$out" && mkdir -p "$out" || exit 1
LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" \
  "$exe" gui --preset contact --res 48 --size 1280x800 --script "$script" --screenshot-dir "$out" \
  --recent-files "" || { echo "isokit-opdesigner gui failed"; exit 1; }
"$check" "$out/studio-report.json" || exit 1
# The spec on the command line: opened as the document and added to the recent files.
"$exe" generate --preset bulge --res 24 --out "$out/bulge.npy" >/dev/null 2>&1 || exit 1
LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s "-screen 0 1280x1024x24" \
  "$exe" gui "$out/bulge.json" --script "$(dirname "$script")/gui_open.json" --screenshot-dir "$out" \
  --report "$out/open-report.json" --recent-files "$out/recent.json" || { echo "gui SPEC failed"; exit 1; }
grep -q '"resolution": 24' "$out/open-report.json" || { echo "FAIL: gui SPEC did not open the 24³ spec"; exit 1; }
grep -q 'bulge.json' "$out/recent.json" || { echo "FAIL: the opened spec is not in the recent files"; exit 1; }
echo "ok  : gui SPEC opened the spec and listed it in the recent files"
if [ "${ISOKIT_UPDATE_DOC_IMAGES:-0}" = 1 ]; then
  for name in studio-before studio-dragged studio-check; do
    cp "$out/$name.png" "$doc_images/$name.png" || exit 1
  done
  echo "copied the screenshots to $doc_images"
fi
