#!/usr/bin/env bash
# Builds the fuzz harnesses (clang, libFuzzer, ASan + UBSan) in build-fuzz/ and runs each for
# FUZZ_SECONDS (default 60) on one core, starting from fuzz/corpus/<h> and fuzz/regressions/<h>.
# New corpus entries go to build-fuzz/corpus/<h> (not into the repository); a crash, sanitizer
# report, leak, timeout (> 10 s per input) or out-of-memory (> 2 GB) is saved to
# build-fuzz/artifacts/<h>/ and makes the script exit 1 (harnesses that do not configure or build:
# exit 3, so CI can tell a broken build from a finding). A table of runs, seconds and crashes is
# printed and written to build-fuzz/fuzz-summary.txt.
#   fuzz/run.sh [HARNESS...]          FUZZ_SECONDS=300 fuzz/run.sh lcm_decode
# To replay a crash: build-fuzz/fuzz_<h> build-fuzz/artifacts/<h>/crash-...; once fixed, copy it to
# fuzz/regressions/<h>/ (ctest replays it: fuzz_regressions_<h>).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${FUZZ_BUILD_DIR:-build-fuzz}
SECONDS_EACH=${FUZZ_SECONDS:-60}
JOBS=${FUZZ_BUILD_JOBS:-$(nproc)}
CCACHE=()
command -v ccache >/dev/null && CCACHE=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
if [ ! -f "$BUILD/CMakeCache.txt" ]; then
  cmake -S fuzz -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_C_COMPILER=clang "${CCACHE[@]}" > "$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 3; }
fi
cmake --build "$BUILD" -j"$JOBS" || { echo "fuzz: the harnesses do not build" >&2; exit 3; }
harnesses=("$@")
if [ ${#harnesses[@]} -eq 0 ]; then
  for f in fuzz/harness/*.cc; do harnesses+=("$(basename "$f" .cc)"); done
fi
summary="$BUILD/fuzz-summary.txt"
printf "%-14s %12s %8s %8s\n" harness runs seconds crashes | tee "$summary"
failed=0
for h in "${harnesses[@]}"; do
  corpus="$BUILD/corpus/$h" artifacts="$BUILD/artifacts/$h"
  mkdir -p "$corpus" "$artifacts"
  seeds=()
  for d in "fuzz/corpus/$h" "fuzz/regressions/$h"; do [ -d "$d" ] && seeds+=("$d"); done
  log="$BUILD/fuzz-$h.log"
  before=$(find "$artifacts" -type f | wc -l)
  t0=$(date +%s)
  set +e
  "$BUILD/fuzz_$h" -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/" "$corpus" "${seeds[@]}" > "$log" 2>&1
  rc=$?
  set -e
  secs=$(( $(date +%s) - t0 ))
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  crashes=$(( $(find "$artifacts" -type f | wc -l) - before ))
  if [ $rc -ne 0 ] && [ $crashes -eq 0 ]; then crashes=1; fi
  printf "%-14s %12s %8s %8s\n" "$h" "${runs:-0}" "${secs:-?}" "$crashes" | tee -a "$summary"
  if [ $crashes -ne 0 ]; then
    failed=1
    echo "fuzz: $h failed (exit $rc); the end of $log:" >&2
    tail -40 "$log" >&2
  fi
done
exit $failed
