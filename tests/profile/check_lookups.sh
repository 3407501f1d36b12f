#!/usr/bin/env bash
# linespace-profile --lookups collects the lookups of a nearest-first walk: the reference kernel's, so
# their number and answers must be what `linespace-cpu trace --traversal reference` counts on the same
# rays; a structure without a Line Space, or a two-level one, is refused with exit 2.
#   tests/profile/check_lookups.sh BUILD_DIR
# shellcheck source=tests/profile/setup.sh
source "$(dirname "$0")/setup.sh"

for scene in builtin:cornell builtin:generated:3000:4:2; do
  "$cpu" rays --scene "$scene" --kind diffuse --count 3000 --seed 3 --out "$tmp/rays" > /dev/null 2>&1
  for structure in f-ls:4:4 f-ls:6:6; do
    trace=$("$cpu" trace --scene "$scene" --structure "$structure" --ls-min-triangles 0 --rays "$tmp/rays" \
      --traversal reference --hits "$tmp/hits" 2>&1 | grep '^line space:')
    expected=$(echo "$trace" | awk '{ gsub(",", ""); l = $3; e = $5; a = $8;
      printf "%d lookups for 3000 rays (%.2f a ray): %.0f %% accepted, %.0f %% empty, %.0f %% refused",
             l, l / 3000, 100 * a / l, 100 * e / l, 100 * (l - a - e) / l }')
    got=$("$profile" "$scene" "$structure" "$tmp/rays" --ls-min-triangles 0 --lookups --repeat 1 | head -1)
    [[ $got == "$expected" ]] || fail "$scene $structure: '$got', the reference trace: '$expected'"
    [[ $got =~ ^[1-9] ]] || fail "$scene $structure: no lookups, the check checks nothing"
  done
done

for structure in bvh 2l-ls:2:4; do
  rc=0
  "$profile" builtin:cornell "$structure" "$tmp/rays" --lookups > /dev/null 2> "$tmp/err" || rc=$?
  [[ $rc == 2 ]] || fail "$structure: exit $rc, expected 2"
  grep -q -- "--lookups" "$tmp/err" || fail "$structure: no message naming --lookups: $(cat "$tmp/err")"
done
echo "linespace-profile --lookups: the reference kernel's lookups; bvh and 2l-ls refused"
