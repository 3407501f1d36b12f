#!/usr/bin/env bash
# CI after the README's test command: the fast path's same-answers tests (tests/test_wide_bvh.cpp)
# built with LINESPACE_ISA=avx2 (preset avx2, build/avx2).  There the order-free tree is 8 wide by
# default and tests a node's boxes in one AVX batch; the portable build runs its 8-wide trees in two
# SSE2 batches, so this is the only place the AVX walk is checked against the reference.
# x86-64-v3 needs AVX2, BMI1/2, FMA, F16C, LZCNT and MOVBE: on a CPU without them it says so and
# runs nothing (it does not report a pass).
set -euo pipefail
cd "$(dirname "$0")/.."
# LZCNT ("abm" in /proc/cpuinfo) is the one a virtual machine may execute and not list (seen on an
# AMD EPYC guest, 2026-12-04): where the flag is missing, the instruction itself is asked.  A CPU
# without it decodes lzcnt as bsr, which gives 0, not 31, for the input 1.
lzcnt_runs() {
  local dir
  dir=$(mktemp -d)
  printf '%s\n' 'int main(int argc, char**) { unsigned r; asm volatile("lzcnt %1, %0" : "=r"(r) : "r"(unsigned(argc)));' \
    '  return r == 31u ? 0 : 1; }' > "$dir/lzcnt.cpp"
  local ok=1
  c++ -O2 "$dir/lzcnt.cpp" -o "$dir/lzcnt" 2>/dev/null && "$dir/lzcnt" && ok=0
  rm -rf "$dir"
  return $ok
}
for flag in avx2 bmi1 bmi2 fma f16c abm movbe; do
  grep -qw "$flag" /proc/cpuinfo && continue
  if [[ $flag == abm ]] && lzcnt_runs; then
    echo "== avx2 tests: /proc/cpuinfo does not list abm, but this CPU executes lzcnt"
    continue
  fi
  echo "== avx2 tests: NOT RUN: this CPU lacks $flag (x86-64-v3)"
  exit 0
done
start=$SECONDS
echo "== avx2 tests: build"
cmake --preset avx2 >/dev/null
cmake --build --preset avx2 --target test_wide_bvh
echo "== avx2 tests: fast path against the reference"
build/avx2/tests/test_wide_bvh
echo "== avx2 tests: $((SECONDS - start)) s"
