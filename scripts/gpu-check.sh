#!/usr/bin/env bash
# One prepared run on whatever Vulkan device a machine has, from the bundle that
# scripts/make-gpu-bundle.sh makes (gpu/README.md says how to run it on a GPU machine):
#   1. the device's name and driver (linespace-gpu devices), and where every library came from;
#   2. linespace-validate candidates (Line Space structures) and hits (bvh, 2l-bvh, f-ls:8:6,
#      2l-ls:4:6) on two scenes: mismatch counts and the first mismatches;
#   3. linespace-gpu bench of those four and the paper's N = 10 configurations on each scene in the
#      bundle: MRays/s, ratios to this device's own F-BVH, beside the paper's GTX 1080 figures;
#   4. linespace-validate rmse --device cpu and --device gpu, from bounce 1: one row per structure.
# Every step runs under `timeout` with its share of the time; one that runs out is recorded as
# "timed out" and the next begins.  Writes OUT/gpu-check.json, OUT/gpu-check.md and
# OUT/gpu-check-logs.tar.gz (every command's output).
#   scripts/gpu-check.sh [--quick] [--out DIR] [--bundle ARCHIVE|DIR] [--budget SECONDS]
#     --quick    the same steps small (CI runs it on lavapipe: about 75 s on 2 cores)
#     --out      default out/gpu-check
#     --bundle   default build/gpu-bundle.tar.gz (or an unpacked bundle folder)
#     --budget   the seconds all steps may take together (default 445; --quick 600)
# The full run takes at most 7.5 minutes (the step shares below).  Needs bash, tar, gzip, timeout
# and python3 (standard library only: the report) on the host; nothing else of the host is used
# but its Vulkan driver.  Exit status: 0 all steps ran and nothing differs; 1 a step failed, timed
# out or found mismatches (the outputs are written all the same); 2 bad usage or no bundle.
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
fail() { echo "gpu-check: $*" >&2; exit 2; }

quick=0
out=out/gpu-check
bundle=build/gpu-bundle.tar.gz
budget_flag=
while (($#)); do
  case $1 in
    --quick) quick=1; shift ;;
    --out) (($# >= 2)) || fail "--out needs a folder"; out=$2; shift 2 ;;
    --bundle) (($# >= 2)) || fail "--bundle needs an archive or a folder"; bundle=$2; shift 2 ;;
    --budget) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || fail "--budget needs a whole number of seconds"; budget_flag=$2; shift 2 ;;
    -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) fail "unknown argument '$1' (see --help)" ;;
  esac
done
command -v python3 >/dev/null || fail "python3 is needed for the report (standard library only)"
command -v timeout >/dev/null || fail "timeout (coreutils) is needed"
# The bundle first: a run refused for want of one leaves no empty --out folder behind.
[[ -d $bundle || -f $bundle ]] || fail "no bundle at $bundle (scripts/make-gpu-bundle.sh makes it)"
mkdir -p "$out" || fail "cannot make $out"
out=$(cd "$out" && pwd)
work=$(mktemp -d "${TMPDIR:-/tmp}/gpu-check.XXXXXX") || fail "cannot make a temporary folder"
trap 'rm -rf "$work"' EXIT
logs=$work/logs
mkdir -p "$logs"

if [[ -d $bundle ]]; then
  b=$(cd "$bundle" && pwd)
elif [[ -f $bundle ]]; then
  tar -C "$work" -xzf "$bundle" 2> "$work/tar.err" || fail "cannot unpack $bundle: $(grep -m 1 . "$work/tar.err")"
  b=$work/gpu-bundle
else
  fail "no bundle at $bundle (scripts/make-gpu-bundle.sh makes it)"
fi
[[ -x $b/bin/linespace-gpu && -x $b/bin/linespace-validate && -x $b/lib/ld-linux-x86-64.so.2 ]] ||
  fail "$bundle is not a GPU bundle (no bin/linespace-gpu, bin/linespace-validate, lib/ld-linux-x86-64.so.2)"
started=$(date +%s)

# The host's Vulkan drivers: their ICD files rewritten with the library's absolute path (the bundle's
# loader would look a bare name up without the host's LD_LIBRARY_PATH, where a GPU driver often
# lies), and the drivers' folders, which the wrappers search after the bundle's own.
python3 "$here/gpu_check.py" icd "$work/icd" > "$logs/icd.txt" 2>&1 || true
drivers=$(sed -n 's/^VK_DRIVER_FILES=//p' "$logs/icd.txt")
extra=$(sed -n 's/^LINESPACE_EXTRA_LIBRARY_PATH=//p' "$logs/icd.txt")
# The programs run in a cleared environment: only what is set here reaches them.
envs=(env -i "PATH=/usr/bin:/bin" "HOME=$work" "TMPDIR=$work" "LINESPACE_EXTRA_LIBRARY_PATH=$extra")
[[ -n $drivers ]] && envs+=("VK_DRIVER_FILES=$drivers" "VK_ICD_FILENAMES=$drivers")
[[ -n ${LP_NUM_THREADS:-} ]] && envs+=("LP_NUM_THREADS=$LP_NUM_THREADS")
gpu=("${envs[@]}" "$b/bin/linespace-gpu")
validate=("${envs[@]}" "$b/bin/linespace-validate")

# Scenes: the real ones in the bundle, else built-in ones.  The cross-checks take the first two.
scenes=(builtin:cornell)
for s in fireplace breakfast bunny; do [[ -f $b/scenes/$s.glb ]] && scenes+=("$b/scenes/$s.glb"); done
four=bvh,2l-bvh,f-ls:8:6,2l-ls:4:6
n10=f-ls:4:10,f-ls:6:10,f-ls:8:10,2l-ls:0:10,2l-ls:4:10,2l-ls:6:10
if ((quick)); then
  ((${#scenes[@]} > 1)) || scenes+=(builtin:generated:20000:8:1)
  check_scenes=("${scenes[0]}" "${scenes[1]}")
  bench_scenes=("${scenes[0]}")
  hit_rays=2000 bench_rays=20000 bench_repeat=1 rmse_size=32x32 rmse_spp=2 rmse_scene=builtin:cornell
  t_cand=60 t_hits=30 t_bench=60 t_bench10=0 t_rmse=60 budget=600
else
  ((${#scenes[@]} > 1)) || scenes+=(builtin:instances)
  check_scenes=("${scenes[0]}" "${scenes[1]}")
  bench_scenes=("${scenes[@]}")
  hit_rays=100000 bench_rays=1000000 bench_repeat=5 rmse_size=128x128 rmse_spp=4 rmse_scene=${scenes[1]}
  # Shares: 30 + 4 x 20 + 8 x 8 + 4 x (20 + 25) (+ 25 for bunny's larger builds) + 2 x 30 = 439 s.
  t_cand=20 t_hits=8 t_bench=20 t_bench10=25 t_rmse=30 budget=445
fi

[[ -n $budget_flag ]] && budget=$budget_flag

# step ID KIND SCENE STRUCTURES SECONDS COMMAND...: runs COMMAND under timeout, its output into
# logs/ID.out and logs/ID.err, and a line into steps.tsv (the report reads both).
# A step also ends when the whole run's budget does; one with under 3 s left is skipped (exit "-").
step() {
  local id=$1 kind=$2 scene=$3 structures=$4 seconds=$5
  shift 5
  local t0 t1 rc left=$((started + budget - $(date +%s)))
  ((seconds > left)) && seconds=$left
  t0=$(date +%s.%N)
  if ((seconds < 3)); then
    rc=-
    : > "$logs/$id.out"
    echo "skipped: the run's time budget was spent" > "$logs/$id.err"
  else
    timeout -k 3 "$seconds" "$@" > "$logs/$id.out" 2> "$logs/$id.err"
    rc=$?
  fi
  t1=$(date +%s.%N)
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$id" "$kind" "$scene" "$structures" "$seconds" \
    "$(awk -v a="$t0" -v b="$t1" 'BEGIN {printf "%.1f", b - a}')" "$rc" >> "$logs/steps.tsv"
  printf 'gpu-check: %-28s %-10s %s: exit %s\n' "$id" "$kind" "$structures" "$rc" >&2
}
label() { local s=${1##*/}; echo "${s%.glb}" | tr ':' '_'; }

step devices devices - - 15 "${gpu[@]}" devices --json
# Where each library came from: the program's own loader with the loader's file log (the wrapper's
# shell would log its own libraries too).
step libraries libraries - - 15 env -i LD_DEBUG=files "${envs[@]:2}" "$b/lib/ld-linux-x86-64.so.2" \
  --library-path "$b/lib:$b/lib-driver${extra:+:$extra}" "$b/libexec/linespace-gpu" devices
for scene in "${check_scenes[@]}"; do
  l=$(label "$scene")
  for s in f-ls:8:6 2l-ls:4:6; do
    step "candidates-$l-${s//:/_}" candidates "$scene" "$s" "$t_cand" "${validate[@]}" candidates --scene "$scene" --structure "$s"
  done
  for s in ${four//,/ }; do
    step "hits-$l-${s//:/_}" hits "$scene" "$s" "$t_hits" "${validate[@]}" hits --scene "$scene" --structure "$s" --count "$hit_rays"
  done
done
for scene in "${bench_scenes[@]}"; do
  l=$(label "$scene")
  extra_time=0
  [[ $l == bunny ]] && extra_time=$t_bench10  # 4.8 M world triangles: the flat builds take longer
  step "bench-$l" bench "$scene" "$four" $((t_bench + extra_time)) "${gpu[@]}" bench --scene "$scene" --structures "$four" \
    --count "$bench_rays" --repeat "$bench_repeat" --json
  ((t_bench10)) && step "bench10-$l" bench "$scene" "$n10" "$t_bench10" "${gpu[@]}" bench --scene "$scene" \
    --structures "$n10" --count "$bench_rays" --repeat "$bench_repeat" --json
done
for device in cpu gpu; do
  step "rmse-$device" rmse "$rmse_scene" "$four" "$t_rmse" "${validate[@]}" rmse --scene "$rmse_scene" --structures "$four" \
    --bounces 1 --spp "$rmse_spp" --size "$rmse_size" --device "$device" --out "$work/rmse-$device"
  [[ -f $work/rmse-$device/rmse.json ]] && cp "$work/rmse-$device/rmse.json" "$logs/rmse-$device.json"
done

elapsed=$(($(date +%s) - started))
python3 "$here/gpu_check.py" report "$logs" "$out" --mode "$( ((quick)) && echo quick || echo full)" \
  --seconds "$elapsed" --bundle "$b"
rc=$?
tar -C "$work" -czf "$out/gpu-check-logs.tar.gz" logs icd 2>/dev/null || tar -C "$work" -czf "$out/gpu-check-logs.tar.gz" logs
exit $rc
