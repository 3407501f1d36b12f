#!/usr/bin/env bash
# CI after the README's test command: the suite under ASan + UBSan, the threaded tests under TSan and
# a time-boxed libFuzzer run of every harness.  Each in its own build folder (build/asan, build/tsan,
# build/fuzz), so the release build is never touched.  docs/robustness.md explains it.
#
#   scripts/run-sanitizers.sh [asan] [tsan] [fuzz]   (default: all three)
#   FUZZ_SECONDS=600 scripts/run-sanitizers.sh fuzz  (longer local fuzzing; default 60 s per harness)
set -euo pipefail
cd "$(dirname "$0")/.."

steps=("$@")
((${#steps[@]})) || steps=(asan tsan fuzz)
fuzz_seconds="${FUZZ_SECONDS:-60}"
jobs="$(nproc)"

timed() {  # timed NAME COMMAND...: runs it and prints its wall time
  local name="$1" start=$SECONDS
  shift
  echo "== $name"
  "$@"
  echo "== $name: $((SECONDS - start)) s"
}

build() {  # build PRESET [TARGETS...]
  local preset="$1"
  shift
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset" -- "$@"
}

for step in "${steps[@]}"; do
  case "$step" in
    asan)
      timed "ASan + UBSan: build" build asan
      timed "ASan + UBSan: whole test suite" ctest --preset asan -j "$jobs"
      ;;
    tsan)
      # Only what runs threads (label `parallel`): the TBB builders, trace_rays, the path tracer, the
      # numerical extremes, and the checks of the TSan setup itself; the target builds just those.
      timed "TSan: build" build tsan parallel_tests
      timed "TSan: parallel tests" ctest --preset tsan -j "$jobs"
      ;;
    fuzz)
      if ! command -v clang++-14 >/dev/null; then
        echo "fuzz: clang++-14 missing (scripts/setup.sh installs clang-14 and libclang-rt-14-dev)" >&2
        exit 1
      fi
      timed "fuzz: build" build fuzz fuzz_gltf fuzz_mesh fuzz_structure_name
      for h in gltf mesh structure_name; do
        # A scratch copy of the seeds: new inputs the fuzzer finds are not written into the repository.
        work="build/fuzz/corpus_$h"
        mkdir -p "$work"
        cp -n tests/fuzz/corpus/"$h"/* "$work"/ 2>/dev/null || true
        timed "fuzz: $h for ${fuzz_seconds} s" build/fuzz/tests/fuzz/fuzz_"$h" -max_total_time="$fuzz_seconds" \
          -rss_limit_mb=2048 -malloc_limit_mb=1024 -timeout=10 -print_final_stats=1 \
          -artifact_prefix="build/fuzz/crash_${h}_" "$work"
      done
      ;;
    *)
      echo "run-sanitizers: unknown step '$step' (expected asan, tsan or fuzz)" >&2
      exit 2
      ;;
  esac
done
