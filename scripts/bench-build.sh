#!/usr/bin/env bash
# Build milliseconds of the F-BVH and the 2L-BVH beside Embree 3's high-quality build of the same scene,
# medians of RUNS runs of `linespace-cpu bench` (Embree builds in the same runs as ours).
#   scripts/bench-build.sh [SCENE ...]        default: the built-in scenes and assets/real/*.glb
#   RUNS=3                                    runs per scene
#   LINESPACE_CPU=build/release/cpu/linespace-cpu
#   COMPARE=/path/to/other/linespace-cpu      also time another build (e.g. an older commit), the two
#                                             binaries alternating run by run
# Prints a Markdown table (milliseconds; "x" = ours / Embree).  docs/performance.md, "Build speed".
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${LINESPACE_CPU:-build/release/cpu/linespace-cpu}
RUNS=${RUNS:-3}
fail() { echo "bench-build: $*" >&2; exit 2; }
[[ -x $BIN ]] || fail "$BIN is not built (scripts/run-demo.sh builds it)"
[[ $RUNS =~ ^[1-9][0-9]*$ ]] || fail "RUNS=$RUNS is not a positive integer"
[[ -z ${COMPARE:-} || -x $COMPARE ]] || fail "COMPARE=$COMPARE is not an executable"
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT  # also when a run fails
scenes=("$@")
if [[ ${#scenes[@]} -eq 0 ]]; then
  scenes=(builtin:cornell builtin:generated:143000:49:1 builtin:instances)
  for f in assets/real/*.glb; do [[ -e $f ]] && scenes+=("$f"); done
fi

median() { sort -g | awk '{v[NR] = $1} END {if (NR) print NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }  # nothing of nothing
# bench's last column is the build milliseconds of each structure and of Embree.
times() { "$1" bench --scene "$2" --count 1000 --repeat 1 --structures bvh,2l-bvh | awk '$1 == "bvh" || $1 == "2l-bvh" || $1 == "embree" {print $1, $NF}'; }

header="| scene | F-BVH ms | Embree HQ ms | F-BVH / Embree | 2L-BVH ms |"
rule="|---|---|---|---|---|"
[[ -n ${COMPARE:-} ]] && header+=" F-BVH ms (COMPARE) | its Embree ms | F-BVH / Embree (COMPARE) |" && rule+="---|---|---|"
echo "$header"
echo "$rule"
for scene in "${scenes[@]}"; do
  : > "$tmp"
  for ((run = 1; run <= RUNS; ++run)); do
    echo "  $scene: run $run of $RUNS" >&2
    times "$BIN" "$scene" | sed 's/^/new /' >> "$tmp"
    [[ -n ${COMPARE:-} ]] && times "$COMPARE" "$scene" | sed 's/^/old /' >> "$tmp"
  done
  pick() { awk -v w="$1" -v s="$2" '$1 == w && $2 == s {print $3}' "$tmp" | median; }
  bvh=$(pick new bvh); emb=$(pick new embree); two=$(pick new 2l-bvh)
  [[ -n $bvh && -n $emb && -n $two ]] || fail "$BIN printed no build times for $scene"
  line="| $scene | $bvh | $emb | $(awk -v a="$bvh" -v b="$emb" 'BEGIN {printf "%.2f", a / b}')x | $two |"
  if [[ -n ${COMPARE:-} ]]; then
    obvh=$(pick old bvh); oemb=$(pick old embree)
    [[ -n $obvh && -n $oemb ]] || fail "COMPARE=$COMPARE printed no build times for $scene (not a linespace-cpu?)"
    line+=" $obvh | $oemb | $(awk -v a="$obvh" -v b="$oemb" 'BEGIN {printf "%.2f", a / b}')x |"
  fi
  echo "$line"
done
