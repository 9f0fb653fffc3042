#!/usr/bin/env bash
# test/prism/test_prism_graded.sh: vm-prism's defaults on the demo aircraft
# as vm-surface --size graded remeshes it (11,937 vertices). With the first
# heights raised to the wall's edges / 30 (--max-aspect), the columns' own
# first split was not valid at any multiplier there and the marching
# stopped at its first split (1 layer of 20, exit 0 with a warning, 918
# prisms failing a 3-tet split); the marching now takes the schedule's
# common split where the own shares are not valid. Asserts: exit 0, all 20
# layers, valid and verified, every first height within [h1, longest wall
# edge / 30] as the JSON says, the largest growth at most the run's before
# the change (10.7 with --max-aspect 0).
# usage: test_prism_graded.sh VM_PRISM VM_GEN VM_SURFACE
set -u
prism=$1 gen=$2 surf=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
num() { sed -n "s/.*\"$1\": \([0-9.eE+-]*\).*/\1/p" "$2"; }
"$gen" aircraft "$dir/a.stl" 2>/dev/null && "$surf" -q --size graded "$dir/a.stl" "$dir/s.vmsh" 2>"$dir/s.err"
check '[ $? -eq 0 ]' "vm-gen aircraft, vm-surface --size graded"
"$prism" --json --threads 2 "$dir/s.vmsh" "$dir/p.vmsh" >"$dir/p.json" 2>"$dir/p.err"
rc=$?
check '[ $rc -eq 0 ]' "vm-prism exits 0 (rc $rc)"
check '! grep -q "marching stopped" "$dir/p.err"' "the marching does not stop early"
check '[ "$(num layers "$dir/p.json")" = 20 ] && grep -q "\"valid\": true, \"verified\": true" "$dir/p.json"' "20 layers, valid and verified"
grep -E "own shares|first height" "$dir/p.err" | sed 's/^/    /'
h1=$(num first_height "$dir/p.json") hmax=$(num first_height_max "$dir/p.json") g=$(num growth_max "$dir/p.json")
check '[ "$(num first_raised "$dir/p.json")" -gt 0 ] && awk "BEGIN{exit !($hmax > $h1)}"' "first heights raised ($h1 to $hmax at $(num first_raised "$dir/p.json") columns)"
check 'awk "BEGIN{exit !($g <= 10.7)}"' "largest growth $g <= 10.7"
exit $fail
