#!/usr/bin/env bash
# CI after the README's test command: the fast path's same-answers tests (tests/test_wide_bvh.cpp)
# built with LINESPACE_ISA=avx2 (preset avx2, build/avx2).  There the order-free tree is 8 wide by
# default and tests a node's boxes in one AVX batch; the portable build runs its 8-wide trees in two
# SSE2 batches, so this is the only place the AVX walk is checked against the reference.
# x86-64-v3 needs AVX2, BMI1/2, FMA, F16C, LZCNT and MOVBE: on a CPU without them it says so and
# runs nothing (it does not report a pass).
set -euo pipefail
cd "$(dirname "$0")/.."
for flag in avx2 bmi1 bmi2 fma f16c abm movbe; do
  if ! grep -qw "$flag" /proc/cpuinfo; then
    echo "== avx2 tests: NOT RUN: this CPU lacks $flag (x86-64-v3)"
    exit 0
  fi
done
start=$SECONDS
echo "== avx2 tests: build"
cmake --preset avx2 >/dev/null
cmake --build --preset avx2 --target test_wide_bvh
echo "== avx2 tests: fast path against the reference"
build/avx2/tests/test_wide_bvh
echo "== avx2 tests: $((SECONDS - start)) s"
