#!/usr/bin/env bash
# linespace-profile --skip leaves work out of a Line Space structure's fast path and says so: without
# lookups a Line Space at the root (f-ls:0:N, every triangle below it) leaves no ray a hit, and a
# structure with one at depth 4 still has some.  Paths and queries that do not know --skip (the
# reference, Embree, any hit, --lookups), a structure without Line Space nodes and an unknown value
# are refused with exit 2.
#   tests/profile/check_skip.sh BUILD_DIR
# shellcheck source=tests/profile/setup.sh
source "$(dirname "$0")/setup.sh"

"$cpu" rays --scene builtin:cornell --kind diffuse --count 2000 --seed 3 --out "$tmp/rays" > /dev/null 2>&1
hits() { sed -n 's/.*, \([0-9]*\) of 2000 rays hit$/\1/p'; }
out=$("$profile" builtin:cornell f-ls:0:4 "$tmp/rays" --ls-min-triangles 0 --skip lookups)
[[ $out == "f-ls:0:4 without lookups, fast path: "* ]] || fail "the line does not say what was left out: $out"
[[ $(hits <<< "$out") == 0 ]] || fail "a Line Space at the root without lookups still hit: $out"
full=$("$profile" builtin:cornell f-ls:0:4 "$tmp/rays" --ls-min-triangles 0 | hits)
[[ $full -gt 0 ]] || fail "f-ls:0:4 hits nothing even with its lookups: the check checks nothing"
out=$("$profile" builtin:cornell f-ls:4:4 "$tmp/rays" --skip refused-walks)
[[ $out == "f-ls:4:4 without refused walks, fast path: "* ]] || fail "the line does not say what was left out: $out"
[[ $(hits <<< "$out") -gt 0 ]] || fail "f-ls:4:4 without refused walks hit nothing: $out"

rc=0
"$profile" builtin:cornell bvh "$tmp/rays" --skip lookups > /dev/null 2> "$tmp/err" || rc=$?
[[ $rc == 2 ]] || fail "bvh --skip lookups: exit $rc, expected 2"
grep -q -- "--skip needs a structure with Line Space nodes" "$tmp/err" || fail "bvh --skip lookups: $(cat "$tmp/err")"

for flags in "--skip lookups --reference" "--skip lookups --embree" "--skip refused-walks --any-hit" \
             "--skip lookups --lookups" "--skip everything"; do
  rc=0
  # shellcheck disable=SC2086  # flags is a list of flags
  "$profile" builtin:cornell f-ls:4:4 "$tmp/rays" $flags > /dev/null 2> "$tmp/err" || rc=$?
  [[ $rc == 2 ]] || fail "$flags: exit $rc, expected 2"
  grep -q -- "--skip" "$tmp/err" || fail "$flags: no message naming --skip: $(cat "$tmp/err")"
done
echo "linespace-profile --skip: says what it leaves out, leaves it out, and is refused where it cannot"
