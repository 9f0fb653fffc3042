#!/usr/bin/env bash
# test/prism/test_prism_plane.sh: vm-prism on ../shared/data/plane.stl at
# T = 5 % and 20 % of its length, 20 layers (suite "slow": about 50 s, so
# not under the sanitizers): valid and free of intersections; at 5 % at
# least 93 % of the columns at full thickness, 99 % of those the geometry
# leaves room for (exterior medial radius >= 1.05 T), and every smooth
# column's first side edge within 5 degrees of the wall normal; at 20 % at
# least 65 % at full thickness, 95 % of those with room, and no smooth
# column beyond 5 degrees either.
set -u
prism=("$1" --check-incremental)
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
plane="${VM_SOURCE_ROOT:-.}/../shared/data/plane.stl"
# run_at PERCENT MIN_FULL MIN_REACH: vm-prism at T = PERCENT % of the
# length; exit 0 and valid, no smooth column's first layer beyond 5
# degrees, at least MIN_FULL of the columns at full thickness and
# MIN_REACH of those with room for it, no intersecting pair left
run_at() {
  local pc=$1 min=$2 minr=$3 j="$dir/p$1.json" rc full reach
  "${prism[@]}" -q -t "$(awk -v p="$pc" 'BEGIN { print p / 100 }')" --json "$plane" \
    "$dir/p$pc.vmsh" >"$j" 2>"$dir/p$pc.err"
  rc=$?
  check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$j"' "plane.stl at $pc %: exit 0, valid (got $rc)"
  check 'grep -q "\"normal_dev_over_5deg\": 0," "$j"' "plane.stl at $pc %: no smooth column's first layer beyond 5 degrees ($(grep -o '"normal_dev_max_deg": [0-9.]*' "$j"))"
  full=$(grep -o '"full_fraction": [0-9.e+-]*' "$j" | awk '{print $2}')
  check 'awk -v f="$full" -v m="$min" "BEGIN { exit !(f >= m) }"' "plane.stl at $pc %: at least $min of the columns at full thickness (got $full)"
  reach=$(grep -o '"reach": [0-9.e+-]*' "$j" | awk '{print $2}')
  check 'awk -v f="$reach" -v m="$minr" "BEGIN { exit !(f >= m) }"' "plane.stl at $pc %: at least $minr of the columns with room at full thickness (got $reach)"
  check 'grep -q "\"intersecting_pairs\": 0," "$j"' "plane.stl at $pc %: no intersecting pair left"
}
if [ -f "$plane" ]; then
  # at least 95 %: cutting used to answer crossings of side quads split
  # along one diagonal (fans at sharp trailing edges): 95.3 %; 96.4 %
  # before the slots between parts' layers were opened, 94.9 % since
  # (the columns lowered stand where there is no room for T: of those with
  # room 99.86 % reach it before, 99.84 % since)
  run_at 5 0.93 0.99
  # at least 65 %: cutting ends (it used to run out of rounds on wing tips
  # and leave the restoring undone: 21 % of columns at full thickness, mean
  # 0.72 T; then 61.8 % while cutting answered diagonal-split artefacts);
  # no column beyond 5 degrees: two lying nearly flat stayed tilted while
  # each was stood up alone or with its ring (every such try inverted a
  # prism), until the tilted ones were solved for with their neighbours
  run_at 20 0.65 0.95
else
  echo "skip: $plane not found"
  exit 77
fi
exit $fail
