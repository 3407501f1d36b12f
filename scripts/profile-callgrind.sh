#!/usr/bin/env bash
# Instructions per ray under callgrind: the table of docs/performance.md ("The profile's story").
# Per scene, COUNT diffuse rays (seed SEED) traced on one thread by linespace-profile: each
# structure's fast path (closest hit), bvh's reference path, bvh's occlusion query, and Embree 3's
# rtcIntersect1 and rtcOccluded1 with its own choice of kernels (AVX2 under valgrind) and with its
# SSE2 kernels.  Only the traversal is counted (--toggle-collect), divided by COUNT
# and rounded down; counts do not depend on the machine's load, timings do.  JOBS callgrind runs at a time.
#   scripts/profile-callgrind.sh [SCENE ...]   default: builtin:cornell assets/real/fireplace.glb
#                                              builtin:generated:143000:49:1 (those that exist)
#   COUNT=20000 SEED=3 JOBS=$(nproc) STRUCTURES=bvh,2l-bvh,f-ls:8:6,2l-ls:4:6
#   LS_FLAGS="--ls-min-triangles 0"           Line Space flags for every structure (the paper's setting)
#   LINESPACE_BUILD=build/release
# Prints a Markdown table.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${LINESPACE_BUILD:-build/release}
COUNT=${COUNT:-20000}
SEED=${SEED:-3}
JOBS=${JOBS:-$(nproc)}
STRUCTURES=${STRUCTURES:-bvh,2l-bvh,f-ls:8:6,2l-ls:4:6}
LS_FLAGS=${LS_FLAGS---ls-min-triangles 0}
fail() { echo "profile-callgrind: $*" >&2; exit 2; }
[[ $COUNT =~ ^[1-9][0-9]*$ ]] || fail "COUNT=$COUNT is not a positive integer"
[[ $SEED =~ ^[0-9]+$ ]] || fail "SEED=$SEED is not a non-negative integer"
[[ $JOBS =~ ^[1-9][0-9]*$ ]] || fail "JOBS=$JOBS is not a positive integer"
command -v valgrind >/dev/null || fail "valgrind is not installed (scripts/setup.sh installs it)"
for program in linespace-cpu linespace-profile; do
  [[ -x $BUILD/cpu/$program ]] || fail "$BUILD/cpu/$program is not built (scripts/setup.sh builds it)"
done
scenes=("$@")
if [[ ${#scenes[@]} -eq 0 ]]; then
  scenes=(builtin:cornell)
  [[ -e assets/real/fireplace.glb ]] && scenes+=(assets/real/fireplace.glb)
  scenes+=(builtin:generated:143000:49:1)
fi
IFS=, read -r -a structures <<< "$STRUCTURES"
tmp=$(mktemp -d)
# On any exit, the callgrind runs still going end too (a failure left them running, orphaned).
cleanup() {
  local running
  running=$(jobs -pr)
  # shellcheck disable=SC2086  # a list of pids
  [[ -z $running ]] || kill $running 2> /dev/null || true
  wait 2> /dev/null || true
  rm -rf "$tmp"
}
trap cleanup EXIT

# One job a line: label <TAB> toggle <TAB> linespace-profile arguments after the ray file.
queries() {
  local s
  for s in "${structures[@]}"; do printf '%s\tls::trace_rays*\t%s %s\n' "$s" "$s" "$LS_FLAGS"; done
  printf 'bvh, reference path\tls::trace_rays*\tbvh --reference\n'
  printf 'bvh, occlusion\tls::trace_occlusion*\tbvh --occlusion\n'
  # Embree's own choice of kernels under valgrind is its AVX2 set (valgrind 3.19 has no AVX-512);
  # its SSE2 set is the same instruction set as the portable build's.
  printf 'Embree rtcIntersect1\tls::EmbreeTracer::trace*\tbvh --embree\n'
  printf 'Embree rtcOccluded1\tls::EmbreeTracer::trace*\tbvh --embree --occlusion\n'
  printf 'Embree rtcIntersect1, sse2\tls::EmbreeTracer::trace*\tbvh --embree --embree-isa sse2\n'
  printf 'Embree rtcOccluded1, sse2\tls::EmbreeTracer::trace*\tbvh --embree --occlusion --embree-isa sse2\n'
}

echo "| scene | query | instructions a ray |"
echo "|---|---|---:|"
for si in "${!scenes[@]}"; do
  scene=${scenes[$si]}
  rays=$tmp/$si.rays
  "$BUILD/cpu/linespace-cpu" rays --scene "$scene" --kind diffuse --count "$COUNT" --seed "$SEED" --out "$rays" \
    > /dev/null 2> "$tmp/rays.err" || fail "could not make rays for $scene: $(cat "$tmp/rays.err")"
  qi=0
  while IFS=$'\t' read -r label toggle args; do
    # A job's status is in its .status file: wait -n's would end the script under set -e, silently.
    while (( $(jobs -rp | wc -l) >= JOBS )); do wait -n || true; done
    read -r structure flags <<< "$args"
    (
      status=0
      # shellcheck disable=SC2086  # flags is a list of flags
      valgrind --tool=callgrind --callgrind-out-file=/dev/null "--toggle-collect=$toggle" \
        "$BUILD/cpu/linespace-profile" "$scene" "$structure" "$rays" $flags > /dev/null 2> "$tmp/$si.$qi.log" || status=$?
      echo "$status" > "$tmp/$si.$qi.status"
    ) &
    echo "$label" > "$tmp/$si.$qi.label"
    qi=$((qi + 1))
  done < <(queries)
  wait
  for ((q = 0; q < qi; ++q)); do
    # The program's own reason: the first line of its stderr without valgrind's (==PID==).
    [[ $(cat "$tmp/$si.$q.status") == 0 ]] ||
      fail "$scene, $(cat "$tmp/$si.$q.label"): $(grep -v '^==' "$tmp/$si.$q.log" | head -n 1)"
    refs=$(sed -n 's/.*I *refs: *\([0-9,]*\).*/\1/p' "$tmp/$si.$q.log" | tr -d ,)
    [[ -n $refs ]] || fail "callgrind gave no count for $scene, $(cat "$tmp/$si.$q.label"): $(tail -n 3 "$tmp/$si.$q.log")"
    # Zero: the toggle matched no function (renamed?), which must not pass for a measurement.
    [[ $refs != 0 ]] || fail "nothing counted for $scene, $(cat "$tmp/$si.$q.label"): no function matches its toggle"
    printf '| %s | %s | %s |\n' "$scene" "$(cat "$tmp/$si.$q.label")" \
      "$(LC_ALL=C awk -v r="$refs" -v n="$COUNT" 'BEGIN { x = int(r / n); s = ""; while (x >= 1000) { s = sprintf(",%03d", x % 1000) s; x = int(x / 1000) } print x s }')"
  done
done
