#!/usr/bin/env bash
# Runs each libFuzzer target of a fuzz build (make fuzz; docs/fuzzing.md) for SECONDS, one after
# the other, and prints one table row per target: seconds, executions, cov, ft, corpus, findings.
#   scripts/run-fuzz.sh BUILD_DIR SECONDS [TARGET...]     (targets: glb gltf fbx dae setup spec npy)
# Corpora grow in BUILD_DIR/corpus/<target> (seeded from BUILD_DIR/seeds/<target>); crashes, hangs
# (-timeout) and out-of-memory inputs (-rss_limit_mb; -malloc_limit_mb, the load budget of the
# largest input) are kept under
# BUILD_DIR/findings/<target>/; the full log is BUILD_DIR/findings/<target>.log.
set -uo pipefail
build=${1:?usage: run-fuzz.sh BUILD_DIR SECONDS [TARGET...]}
seconds=${2:?usage: run-fuzz.sh BUILD_DIR SECONDS [TARGET...]}
shift 2
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(glb gltf fbx dae setup spec npy)
timeout_s=${FUZZ_TIMEOUT:-10}
rss_mb=${FUZZ_RSS_MB:-2048}
# Inputs up to max_len bytes (at least the largest seed); one allocation past the load budget of
# such an input (isokit/core/load_budget.h, printed by isokit_fuzz_seeds --budget-mb) is a finding.
max_len=${FUZZ_MAX_LEN:-16384}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

echo "| target | seconds | executions | cov | ft | corpus | findings |"
echo "|---|---|---|---|---|---|---|"
status=0
for t in "${targets[@]}"; do
  exe="$build/fuzz/isokit_fuzz_$t"
  corpus="$build/corpus/$t" findings="$build/findings/$t"
  mkdir -p "$corpus" "$findings"
  # assimp 5.2 leaks, hangs and over-allocates inside itself on malformed FBX / COLLADA files
  # (docs/fuzzing.md): run in process, those targets run without leak detection, in fork mode, and
  # go on after a finding (each is kept), so that they fuzz for the whole time. With
  # ISOKIT_FUZZ_ISOLATE=1 they read as isokit-skin does (assimp in a child process) and, like the
  # other targets, stop at their first finding.
  extra=(-detect_leaks=1)
  case "$t" in
    fbx | dae)
      if [ -z "${ISOKIT_FUZZ_ISOLATE:-}" ] || [ "${ISOKIT_FUZZ_ISOLATE}" = 0 ]; then
        extra=(-detect_leaks=0 -fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1)
      fi
      ;;
  esac
  len=$max_len
  for f in "$build/seeds/$t"/*; do
    [ -f "$f" ] && [ "$(stat -c %s "$f")" -gt "$len" ] && len=$(stat -c %s "$f")
  done
  malloc_mb=$("$build/fuzz/isokit_fuzz_seeds" --budget-mb "$len")
  # Read in a child process (FUZZ_ISOLATE), fbx and dae allocate in that child, which inherits
  # libFuzzer's malloc hook: the load budget would end the child as an "oom" the parent never
  # sees (it gets the InputError). The child has its own limits (the fuzz target: 1 GiB, 5 s).
  case "$t" in
    fbx | dae)
      [ -n "${ISOKIT_FUZZ_ISOLATE:-}" ] && [ "${ISOKIT_FUZZ_ISOLATE}" != 0 ] && malloc_mb=$rss_mb
      ;;
  esac
  start=$(date +%s)
  "$exe" -max_total_time="$seconds" -timeout="$timeout_s" -rss_limit_mb="$rss_mb" -max_len="$len" \
    -malloc_limit_mb="$malloc_mb" "${extra[@]}" -print_final_stats=1 -artifact_prefix="$findings/" \
    "$corpus" "$build/seeds/$t" > "$build/findings/$t.log" 2>&1
  rc=$?
  elapsed=$(( $(date +%s) - start ))
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$build/findings/$t.log" | tail -1 | grep -o '[0-9]*$')
  last=$(grep -E '^#[0-9]+' "$build/findings/$t.log" | tail -1)
  [ -n "$execs" ] || execs=$(grep -oE '^#[0-9]+' <<< "$last" | tr -d '#')
  cov=$(grep -o 'cov: [0-9]*' <<< "$last" | grep -o '[0-9]*')
  ft=$(grep -o 'ft: [0-9]*' <<< "$last" | grep -o '[0-9]*')
  corp=$(grep -o 'corp: [0-9]*' <<< "$last" | grep -o '[0-9]*')
  found=$(find "$findings" -type f | wc -l)
  [ "$rc" -eq 0 ] && [ "$found" -eq 0 ] || status=1
  echo "| $t | $elapsed | ${execs:-?} | ${cov:-?} | ${ft:-?} | ${corp:-?} | $found |"
done
exit $status
