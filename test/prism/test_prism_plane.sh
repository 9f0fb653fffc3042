#!/usr/bin/env bash
# test/prism/test_prism_plane.sh: vm-prism on ../shared/data/plane.stl at
# T = 5 % and 20 % of its length, 20 layers (suite "slow": about 50 s, so
# not under the sanitizers): valid and free of intersections; at 5 % at
# least 95 % of the columns at full thickness and every smooth column's
# first side edge within 5 degrees of the wall normal; at 20 % at least 65 %
# at full thickness and no smooth column beyond 5 degrees either.
set -u
prism=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
plane="${VM_SOURCE_ROOT:-.}/../shared/data/plane.stl"
if [ -f "$plane" ]; then
  "$prism" -q -t 0.05 --json "$plane" "$dir/p5.vmsh" >"$dir/p5.json" 2>"$dir/p5.err"
  rc=$?
  check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/p5.json"' "plane.stl at 5 %: exit 0, valid (got $rc)"
  check 'grep -q "\"normal_dev_over_5deg\": 0," "$dir/p5.json"' "plane.stl at 5 %: no smooth column's first layer beyond 5 degrees ($(grep -o '"normal_dev_max_deg": [0-9.]*' "$dir/p5.json"))"
  # cutting used to answer crossings of side quads split along one
  # diagonal (fans at sharp trailing edges): 95.3 %
  full=$(grep -o '"full_fraction": [0-9.e+-]*' "$dir/p5.json" | awk '{print $2}')
  check 'awk -v f="$full" "BEGIN { exit !(f >= 0.95) }"' "plane.stl at 5 %: at least 95 % of the columns at full thickness (got $full)"
  check 'grep -q "\"intersecting_pairs\": 0," "$dir/p5.json"' "plane.stl at 5 %: no intersecting pair left"
  "$prism" -q -t 0.2 --json "$plane" "$dir/p20.vmsh" >"$dir/p20.json" 2>"$dir/p20.err"
  rc=$?
  check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/p20.json"' "plane.stl at 20 %: exit 0, valid (got $rc)"
  # two columns lying nearly flat stayed tilted while each was stood up
  # alone or with its ring (every such try inverted a prism), until the
  # tilted ones were solved for with their neighbours
  check 'grep -q "\"normal_dev_over_5deg\": 0," "$dir/p20.json"' "plane.stl at 20 %: no smooth column's first layer beyond 5 degrees ($(grep -o '"normal_dev_max_deg": [0-9.]*' "$dir/p20.json"))"
  # cutting ends (it used to run out of rounds on wing tips and leave the
  # restoring undone: 21 % of columns at full thickness, mean 0.72 T; then
  # 61.8 % while cutting answered diagonal-split artefacts)
  full=$(grep -o '"full_fraction": [0-9.e+-]*' "$dir/p20.json" | awk '{print $2}')
  check 'awk -v f="$full" "BEGIN { exit !(f >= 0.65) }"' "plane.stl at 20 %: at least 65 % of the columns at full thickness (got $full)"
  check 'grep -q "\"intersecting_pairs\": 0," "$dir/p20.json"' "plane.stl at 20 %: no intersecting pair left"
else
  echo "skip: $plane not found"
  exit 77
fi
exit $fail
