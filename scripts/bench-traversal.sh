#!/usr/bin/env bash
# Traversal speed beside Embree 3 on the same rays: per scene and structure, the fast path's MRays/s,
# its ratio to Embree's rtcIntersect1 (rtcOccluded1 for KIND=shadow) measured in the same run, and its
# ratio to our scalar reference path; medians over RUNS runs of `linespace-cpu bench` (each run
# itself the median of REPEAT timings, on THREADS threads).
#   scripts/bench-traversal.sh [SCENE ...]    default: the built-in scenes and assets/real/*.glb
#   RUNS=3 REPEAT=3 COUNT=200000 KIND=diffuse STRUCTURES=bvh,2l-bvh,f-ls:8:6,2l-ls:4:6
#   LS_FLAGS="--ls-min-triangles 0"           Line Space flags for every run (the paper's setting)
#   THREADS=0                                 bench --threads: 0 all the CPUs, 2 "two cores" on any machine
#   EMBREE_ISA=best                           Embree's instruction set (bench --embree-isa; sse2 matches
#                                             the portable build's SSE2)
#   LINESPACE_CPU=build/release/cpu/linespace-cpu
#   COMPARE=/path/to/other/linespace-cpu      also time another build (e.g. an older commit) on the same
#                                             scenes, the two binaries alternating run by run; its
#                                             MRays/s and ratio to Embree (in its own runs) in two more columns
# Prints a Markdown table.  docs/performance.md, "Measurements".
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${LINESPACE_CPU:-build/release/cpu/linespace-cpu}
RUNS=${RUNS:-3}
REPEAT=${REPEAT:-3}
COUNT=${COUNT:-200000}
KIND=${KIND:-diffuse}
STRUCTURES=${STRUCTURES:-bvh,2l-bvh,f-ls:8:6,2l-ls:4:6}
LS_FLAGS=${LS_FLAGS---ls-min-triangles 0}
EMBREE_ISA=${EMBREE_ISA:-best}
THREADS=${THREADS:-0}
[[ -x $BIN ]] || { echo "bench-traversal: $BIN is not built (scripts/run-demo.sh builds it)" >&2; exit 2; }
[[ $RUNS =~ ^[1-9][0-9]*$ ]] || { echo "bench-traversal: RUNS=$RUNS is not a positive integer" >&2; exit 2; }
[[ -z ${COMPARE:-} || -x $COMPARE ]] || { echo "bench-traversal: COMPARE=$COMPARE is not an executable" >&2; exit 2; }
scenes=("$@")
if [[ ${#scenes[@]} -eq 0 ]]; then
  scenes=(builtin:cornell builtin:generated:143000:49:1 builtin:instances)
  for f in assets/real/*.glb; do [[ -e $f ]] && scenes+=("$f"); done
fi

header="| scene | structure | fast MRays/s | vs Embree | fast / reference | Embree MRays/s (its ISA) |"
rule="|---|---|---:|---:|---:|---:|"
[[ -n ${COMPARE:-} ]] && header+=" COMPARE fast MRays/s | COMPARE vs Embree |" && rule+="---:|---:|"
echo "$header"
echo "$rule"
bench() {
  # shellcheck disable=SC2086  # LS_FLAGS is a list of flags
  "$1" bench --scene "$2" --kind "$KIND" --count "$COUNT" --repeat "$REPEAT" --structures "$STRUCTURES" \
    --embree-isa "$EMBREE_ISA" --threads "$THREADS" $LS_FLAGS --json
  echo
}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT  # also when a run fails
tmp=$work/runs
old=$work/compare_runs
for scene in "${scenes[@]}"; do
  : > "$tmp"
  : > "$old"
  for ((run = 1; run <= RUNS; ++run)); do
    echo "  $scene: run $run of $RUNS" >&2
    bench "$BIN" "$scene" >> "$tmp"
    if [[ -n ${COMPARE:-} ]]; then bench "$COMPARE" "$scene" >> "$old"; fi
  done
  python3 - "$scene" "$tmp" "$old" "${COMPARE:-}" <<'EOF'
import json, statistics, sys
scene, path, compare_path, compare_program = sys.argv[1:5]
def read(path):
    runs, text = [], open(path).read()
    decoder, at = json.JSONDecoder(), 0
    while True:
        while at < len(text) and text[at].isspace():
            at += 1
        if at >= len(text):
            return runs
        run, at = decoder.raw_decode(text, at)
        runs.append(run)
def medians(runs, name):  # MRays/s, ratio to Embree, fast / reference
    entries = [next(e for e in r["results"] if e["structure"] == name) for r in runs]
    return (statistics.median(e["mrays_per_s"] for e in entries), statistics.median(e["ratio_vs_embree"] for e in entries),
            statistics.median(e["mrays_per_s"] / e["reference_mrays_per_s"] for e in entries))
runs, compare = read(path), read(compare_path)
if compare_program and not compare:
    sys.exit(f"bench-traversal: COMPARE={compare_program} printed no bench results for {scene} (not a linespace-cpu?)")
embree = statistics.median(next(e["mrays_per_s"] for e in r["results"] if e["structure"] == "embree") for r in runs)
isa = runs[0]["embree_isa"]
for name in [e["structure"] for e in runs[0]["results"] if e["structure"] != "embree"]:
    fast, ratio, vs_ref = medians(runs, name)
    line = f"| {scene} | {name} | {fast:.2f} | {ratio:.2f}x | {vs_ref:.2f}x | {embree:.2f} ({isa}) |"
    if compare:
        old_fast, old_ratio, _ = medians(compare, name)
        line += f" {old_fast:.2f} | {old_ratio:.2f}x |"
    print(line)
EOF
done
