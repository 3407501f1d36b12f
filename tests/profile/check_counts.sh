#!/usr/bin/env bash
# linespace-profile's flags: counts are whole numbers in range or exit 2 naming the flag ("3x", "-1"
# and "abc" were read by atoi as 3, a wrapped 4294967295 and 0), as are an unknown flag, a flag
# without its value, --reference with --embree and a bad --ls-budget; --help exits 0; an in-range
# --ls-min-triangles is obeyed: above every subtree's size no Line Space node is left, so f-ls hits
# exactly what bvh hits.
#   tests/profile/check_counts.sh BUILD_DIR
# shellcheck source=tests/profile/setup.sh
source "$(dirname "$0")/setup.sh"

"$cpu" rays --scene builtin:cornell --kind diffuse --count 2000 --seed 3 --out "$tmp/rays" > /dev/null 2>&1
for flags in "--repeat 0" "--repeat 3x" "--repeat x" "--ls-min-triangles -1" "--ls-min-triangles abc" \
             "--ls-min-triangles 4294967296" "--exact-width 5" "--ls-budget nan" "--ls-budget 0"; do
  rc=0
  # shellcheck disable=SC2086  # flags is a flag and its value
  "$profile" builtin:cornell f-ls:0:4 "$tmp/rays" $flags > /dev/null 2> "$tmp/err" || rc=$?
  [[ $rc == 2 ]] || fail "$flags: exit $rc, expected 2"
  grep -q -- "${flags%% *}\|width" "$tmp/err" || fail "$flags: no message naming the flag: $(cat "$tmp/err")"
done

for flags in "--frobnicate" "--repeat" "--reference --embree" "--skip everything"; do
  rc=0
  # shellcheck disable=SC2086  # flags is a list of flags
  "$profile" builtin:cornell f-ls:0:4 "$tmp/rays" $flags > /dev/null 2> "$tmp/err" || rc=$?
  [[ $rc == 2 ]] || fail "$flags: exit $rc, expected 2"
  [[ $(head -1 "$tmp/err") == "linespace-profile: "* ]] || fail "$flags: no reason before the usage: $(cat "$tmp/err")"
done
"$profile" --help | grep -q "^usage: linespace-profile" || fail "--help does not print the usage on stdout"

hits() { sed -n 's/.*, \([0-9]*\) of 2000 rays hit$/\1/p'; }
exact=$("$profile" builtin:cornell bvh "$tmp/rays" | hits)
none=$("$profile" builtin:cornell f-ls:0:4 "$tmp/rays" --ls-min-triangles 4294967295 | hits)
some=$("$profile" builtin:cornell f-ls:0:4 "$tmp/rays" --ls-min-triangles 0 --skip lookups | hits)
[[ $none == "$exact" ]] || fail "f-ls:0:4 with no Line Space node hit $none rays, bvh $exact"
[[ $some != "$exact" ]] || fail "--ls-min-triangles 0 left the root's Line Space out too: the check checks nothing"
echo "linespace-profile: bad flags exit 2 with a reason; --help exits 0; --ls-min-triangles is obeyed"
