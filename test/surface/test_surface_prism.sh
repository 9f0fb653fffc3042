#!/usr/bin/env bash
# test/surface/test_surface_prism.sh: what vm-surface writes with its
# defaults, vm-prism takes, on surfaces built to be hard: a spindle (two
# cone points, a row of 1.8-degree needles, a sharp ring), an icosphere
# oriented inwards, and a graded wing with a sharp trailing edge
# (vm-gen wing: needles 1,500 times longer than wide). The spindle's tips
# stay vertices, bit for bit, its row of needles goes, and the wing's
# grading stays (no remeshing to one edge length); the same shapes through
# --size graded and --size curvature; an assembly of overlapping parts,
# united.
set -u
gen=$1 surf=$2 prism=$3 vmgen=$4 conv=$5
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

"$gen" spindle "$dir/sp.stl"
"$surf" -q --json "$dir/sp.stl" "$dir/sp.vmsh" >"$dir/sp.json" 2>"$dir/sp.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"size\": \"input\"" "$dir/sp.json" && grep -q "\"cones\": 2," "$dir/sp.json"' \
  "spindle: exit 0, input size, two cone points (got $rc: $(cat "$dir/sp.err"))"
check 'grep -q "\"feature_vertices\": [1-9][0-9]*, \"corners_moved\": 0}" "$dir/sp.json"' \
  "spindle: the local deviation is measured at its feature vertices, no corner or tip moved"
below_in=$(sed -n 's/.*"below_in": \([0-9]*\).*/\1/p' "$dir/sp.json")
below=$(sed -n 's/.*"below": \([0-9]*\).*/\1/p' "$dir/sp.json")
check '[ -n "$below" ] && [ "$below" -lt "$below_in" ]' "spindle: fewer slivers ($below_in -> $below)"
"$conv" -q "$dir/sp.vmsh" "$dir/sp.off"
check 'grep -qx "0 0 1" "$dir/sp.off" && grep -qx "0 0 -1" "$dir/sp.off"' "spindle: both tips still vertices, bit for bit"
amin=$(sed -n 's/.*"slivers": {[^}]*"min_angle": \([0-9.e+-]*\),.*/\1/p' "$dir/sp.json")
check 'awk -v a="$amin" "BEGIN { exit !(a > 3) }"' "spindle: the row of 1.8-degree needles is gone (smallest angle $amin)"
"$prism" -q --json -t 0.05 -n 5 "$dir/sp.vmsh" "$dir/spp.vmsh" >"$dir/spp.json" 2>"$dir/spp.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/spp.json"' "spindle: vm-prism takes it ($(tail -n 1 "$dir/spp.err"))"

"$gen" inward "$dir/in.stl"
"$surf" -q --json --iter 20 "$dir/in.stl" "$dir/in.vmsh" >"$dir/in.json" 2>&1
check '[ $? -eq 0 ] && grep -q "\"reoriented\": 1280" "$dir/in.json"' "inward sphere: vm-surface turns it"
"$prism" -q --json -t 0.05 -n 5 "$dir/in.vmsh" "$dir/inp.vmsh" >"$dir/inp.json" 2>"$dir/inp.err"
check '[ $? -eq 0 ] && grep -q "\"valid\": true" "$dir/inp.json"' "inward sphere: vm-prism takes vm-surface's result"

"$vmgen" wing "$dir/w.stl" >/dev/null
"$surf" --json --iter 40 "$dir/w.stl" "$dir/w.vmsh" >"$dir/w.json" 2>"$dir/w.err"
rc=$?
nf=$(sed -n 's/.*"faces": \([0-9]*\), "repair".*/\1/p' "$dir/w.json")
# its rows of needles (1,118 triangles under 1 degree that flips and
# collapses cannot remove) make the stage remesh it to sizes from the
# curvature, to about the count the sliver removal left (4,564)
check '[ $rc -eq 0 ] && [ -n "$nf" ] && [ "$nf" -ge 4000 ] && [ "$nf" -le 6500 ]' \
  "graded wing: exit 0, about the input's count (5,756 triangles in, $nf out; uniform remeshing gave 430)"
needles=$(sed -n 's/.*"needles": \([0-9]*\),.*/\1/p' "$dir/w.json")
wmin=$(sed -n 's/.*"min_angle": \([0-9.e+-]*\), "time".*/\1/p' "$dir/w.json")
check 'grep -q "\"size\": \"curvature\"" "$dir/w.json" && [ "${needles:-0}" -gt 1000 ] && grep -q "remeshing the input to sizes from its curvature" "$dir/w.err" && awk -v a="$wmin" "BEGIN { exit !(a > 10) }"' \
  "graded wing: $needles needles left by the sliver removal, remeshed by the curvature (said), smallest angle $wmin"
check 'grep -q "\"self_intersections\": 0," "$dir/w.json" && grep -q "\"corners_moved\": 0}" "$dir/w.json"' "graded wing: no intersecting pair, the corners kept"
"$prism" -q --json -t 0.2 -n 5 "$dir/w.vmsh" "$dir/wp.vmsh" >"$dir/wp.json" 2>"$dir/wp.err"
reach=$(sed -n 's/.*"medial": {[^}]*"reach": \([0-9.e+-]*\),.*/\1/p' "$dir/wp.json")
check '[ $? -eq 0 ] && grep -q "\"valid\": true" "$dir/wp.json" && awk -v r="$reach" "BEGIN { exit !(r >= 0.98) }"' \
  "graded wing: vm-prism at T = 20 % reaches T at $reach of the columns with room (on the input's needles: 0.037)"
# --size input named: the input's own vertices, needles and all
"$surf" -q --json --iter 10 --size input "$dir/w.stl" "$dir/wi.vmsh" >"$dir/wi.json" 2>"$dir/wi.err"
check '[ $? -eq 0 ] && grep -q "\"size\": \"input\", \"needles\": 0" "$dir/wi.json" && grep -q "\"faces\": 4564, \"repair\"" "$dir/wi.json"' \
  "graded wing, --size input: the input's vertices kept (4,564 triangles after the sliver removal)"
"$prism" -q --json --keep-wall -t 0.05 -n 3 "$dir/wi.vmsh" "$dir/wip.vmsh" >"$dir/wip.json" 2>"$dir/wip.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/wip.json"' "graded wing, --size input: vm-prism --keep-wall takes it ($(tail -n 1 "$dir/wip.err"))"
# vm-prism given the raw wing (needles) runs the surface stage itself: the
# same layers, byte for byte, as vm-surface's defaults and then vm-prism
"$surf" -q "$dir/w.stl" "$dir/wd.vmsh"
"$prism" -q -t 0.05 -n 3 "$dir/wd.vmsh" "$dir/two.vmsh" 2>/dev/null
"$prism" -q --json --report "$dir/rep" -t 0.05 -n 3 "$dir/w.stl" "$dir/one.vmsh" >"$dir/one.json" 2>"$dir/one.err"
check '[ $? -eq 0 ] && cmp -s "$dir/one.vmsh" "$dir/two.vmsh" && grep -q "\"surface_stage\": true, \"needles\": 0," "$dir/one.json"' \
  "raw graded wing: vm-prism's own surface stage gives the layers of vm-surface then vm-prism, byte for byte"
check 'grep -q "surface stage (the wall had needles under 1 degree)</td><td class=\"v\">5756 -&gt; [0-9]* triangles (remeshed" "$dir/rep/index.html"' \
  "and its report says so"

# the uniform remeshing (CGAL) of the wing folds triangles over where its
# details are far finer than the edge length: caught, and the run goes on
# with the input's vertices
"$surf" -q --json --iter 10 --size uniform "$dir/w.stl" "$dir/wu.vmsh" >"$dir/wu.json" 2>"$dir/wu.err"
rc=$?
ro=$(sed -n 's/.*"remesh_opposing": \([0-9]*\).*/\1/p' "$dir/wu.json")
check '[ $rc -eq 0 ] && grep -q "\"opposing\": 0," "$dir/wu.json" && [ -n "$ro" ]' \
  "graded wing, --size uniform: exit 0, nothing turned over in the result (got $rc)"
if [ "${ro:-0}" -gt 0 ]; then
  check 'grep -q "turned $ro triangles over against the input" "$dir/wu.err" && grep -q "\"remeshed\": false" "$dir/wu.json"' \
    "graded wing, --size uniform: the remeshing's $ro folds are said and it is given up"
fi

# the graded and curvature-sized remeshings on the spindle and the wing:
# the tips stay, the slivers go, nothing folds, vm-prism takes the result
for size in graded curvature; do
  "$surf" -q --json --size $size "$dir/sp.stl" "$dir/sp$size.vmsh" >"$dir/sp$size.json" 2>"$dir/sp$size.err"
  rc=$?
  "$conv" -q "$dir/sp$size.vmsh" "$dir/sp$size.off"
  amin=$(sed -n 's/.*"graded": {[^}]*"min_angle": \([0-9.e+-]*\)}.*/\1/p' "$dir/sp$size.json")
  check '[ $rc -eq 0 ] && grep -q "\"remeshed\": true" "$dir/sp$size.json" && grep -qx "0 0 1" "$dir/sp$size.off" && grep -qx "0 0 -1" "$dir/sp$size.off"' \
    "spindle, --size $size: remeshed, both tips still vertices, bit for bit (got $rc: $(tail -n 1 "$dir/sp$size.err"))"
  check 'awk -v a="$amin" "BEGIN { exit !(a > 20) }"' "spindle, --size $size: smallest angle $amin > 20"
  "$prism" -q --json -t 0.05 -n 5 "$dir/sp$size.vmsh" "$dir/spp$size.vmsh" >"$dir/spp$size.json" 2>"$dir/spp$size.err"
  check '[ $? -eq 0 ] && grep -q "\"valid\": true" "$dir/spp$size.json"' "spindle, --size $size: vm-prism takes it"
  "$surf" -q --json --size $size "$dir/w.stl" "$dir/w$size.vmsh" >"$dir/w$size.json" 2>"$dir/w$size.err"
  rc=$?
  check '[ $rc -eq 0 ] && grep -q "\"remeshed\": true" "$dir/w$size.json" && grep -q "\"opposing\": 0," "$dir/w$size.json" && grep -q "\"self_intersections\": 0," "$dir/w$size.json"' \
    "graded wing, --size $size: remeshed, nothing turned over, no intersecting pair (got $rc: $(tail -n 1 "$dir/w$size.err"))"
  "$prism" -q --json -t 0.05 -n 3 "$dir/w$size.vmsh" "$dir/wp$size.vmsh" >"$dir/wp$size.json" 2>"$dir/wp$size.err"
  rc=$?
  check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/wp$size.json"' "graded wing, --size $size: vm-prism takes it ($(tail -n 1 "$dir/wp$size.err"))"
done

# an assembly as published models are: a sphere, a bar through it, a box
# inside it (three closed parts, one file): the repair unites them; without
# the union it is refused, and vm-prism sends it through the surface stage
"$gen" assembly "$dir/asm.stl"
"$surf" -q --json "$dir/asm.stl" "$dir/asm.vmsh" >"$dir/asm.json" 2>"$dir/asm.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"components\": 1, \"self_intersections\": 0, \"united\": 3, \"union_pairs\": [1-9]" "$dir/asm.json"' \
  "assembly: vm-surface unites its three parts into one ($(grep -o '"united[^,]*' "$dir/asm.json"))"
check 'grep -q "warning: repair: 3 of the 3 closed components overlap" "$dir/asm.err"' "assembly: the union is said on stderr"
"$surf" -q --no-union "$dir/asm.stl" "$dir/asm_no.vmsh" 2>"$dir/asm_no.err"
rc=$?
check '[ $rc -eq 1 ] && grep -q "error: .*self-intersecting surface: 26 pairs" "$dir/asm_no.err" && [ ! -e "$dir/asm_no.vmsh" ]' \
  "assembly: --no-union refuses it, nothing written ($(cat "$dir/asm_no.err"))"
"$prism" -q --json -t 0.05 -n 5 "$dir/asm.stl" "$dir/asmp.vmsh" >"$dir/asmp.json" 2>"$dir/asmp.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/asmp.json" && grep -q "\"surface_stage\": true" "$dir/asmp.json"' \
  "assembly: vm-prism takes the STL through the surface stage ($(tail -n 1 "$dir/asmp.err"))"
"$prism" -q --keep-wall -t 0.05 -n 5 "$dir/asm.stl" "$dir/asmk.vmsh" 2>"$dir/asmk.err"
rc=$?
check '[ $rc -eq 1 ] && grep -q "error: .*the wall intersects itself: 26 pairs" "$dir/asmk.err" && [ ! -e "$dir/asmk.vmsh" ]' \
  "assembly: with --keep-wall vm-prism refuses it ($(cat "$dir/asmk.err"))"

exit $fail
