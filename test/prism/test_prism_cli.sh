#!/usr/bin/env bash
# test/prism/test_prism_cli.sh: vm-prism end to end on the generated demo
# aircraft (coarsest): every output format is written, the .msh is read
# back by vm-quality and checked exactly (--verify: CGAL predicates), and by
# gmsh -check when Gmsh is installed; the --json summary says valid; bad input and usage errors give
# a one-line error, the documented exit code and no output file.
set -u
prism=("$1" --check-incremental) gen=$2 qual=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

# a graded wing (vm-gen wing: cosine chordwise spacing, trailing-edge
# triangles 1,500 times longer than wide, as CAD meshes of wings have),
# extruded as it is (--keep-wall): its thin layer used to be refused ("12
# thin prisms stay degenerate", exit 1) while Gmsh extrudes it; the second
# halving pass takes it
"$gen" wing "$dir/w.stl" >/dev/null
"${prism[@]}" --keep-wall -t 0.05 -n 3 --json "$dir/w.stl" "$dir/w.vmsh" >"$dir/w.json" 2>"$dir/w.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/w.json" && grep -q "\"intersecting_pairs\": 0," "$dir/w.json"' \
  "a graded wing's needles: a valid layer (got $rc)"
check 'grep -q "thin layer: [0-9]* prisms still poor after 60 halvings; halving their neighbourhoods" "$dir/w.err"' \
  "the second pass is said"
"$qual" -q --verify "$dir/w.vmsh" >/dev/null 2>&1
check '[ $? -eq 0 ]' "and vm-quality --verify accepts it"

"$gen" aircraft --resolution 1 "$dir/a.stl" >/dev/null
check '[ -s "$dir/a.stl" ]' "vm-gen aircraft writes the wall"
"${prism[@]}" -t 0.05 -n 4 --json "$dir/a.stl" "$dir/a.msh" >"$dir/a.json" 2>"$dir/a.err"
rc=$?
check '[ $rc -eq 0 ]' "vm-prism on the aircraft exits 0 (got $rc)"
check 'grep -q "\"valid\": true" "$dir/a.json"' "--json says valid"
check 'grep -q "\"inverted_corner_tets\": 0," "$dir/a.json"' "--json: no inverted corner tet"
check 'grep -q "\"intersecting_pairs\": 0," "$dir/a.json"' "--json: no intersecting pair"
check 'grep -q "\"layers\": 4," "$dir/a.json"' "--json: 4 layers"
# the room the geometry leaves: shares in [0, 1], the fill at most 1; a
# column short of T where there is room is warned of, and --min-reach
# turns it into exit 5 (the mesh still written, still valid)
reach=$(grep -o '"reach": [0-9.e+-]*' "$dir/a.json" | awk '{print $2}')
nshort=$(grep -o '"short": [0-9]*' "$dir/a.json" | awk '{print $2}')
check 'grep -Eq "\"medial\": \{\"room\": 0\.[0-9]+, \"reach\": (0\.[0-9]+|1), \"short\": [0-9]+, \"fill\": (0\.[0-9]+|1)," "$dir/a.json"' "--json: the room figures ($(grep -o '"medial": {[^}]*}' "$dir/a.json"))"
if [ "${nshort:-0}" -gt 0 ]; then
  check 'grep -q "warning: $nshort of the [0-9]* columns the geometry leaves room for" "$dir/a.err"' "the short columns with room are warned of"
  rm -f "$dir/mr.vmsh"
  "${prism[@]}" -q -t 0.05 -n 4 --min-reach 100 --json "$dir/a.stl" "$dir/mr.vmsh" >"$dir/mr.json" 2>"$dir/mr.err"
  rc=$?
  check '[ $rc -eq 5 ] && [ -s "$dir/mr.vmsh" ] && grep -q "\"valid\": true" "$dir/mr.json" && grep -q "fewer than --min-reach 100 %" "$dir/mr.err"' "--min-reach 100 with $nshort short columns: exit 5, the mesh written (got $rc)"
  "${prism[@]}" -q -t 0.05 -n 4 --min-reach 50 "$dir/a.stl" "$dir/mr.vmsh" 2>/dev/null
  check '[ $? -eq 0 ]' "--min-reach 50 with $reach of them at T: exit 0"
else
  echo "FAIL: the coarse aircraft at 4 layers has no short column with room (reach $reach): --min-reach is not tested"
  fail=1
fi
# --hold-retries: at T = 15 % the coarse aircraft's springback is held past
# its budget (204 iterations): with the option it goes on with held
# retries (held_steps > 0) and the layer is valid; without, none are taken
"${prism[@]}" -q -t 0.15 -n 4 --json "$dir/a.stl" "$dir/h0.vmsh" >"$dir/h0.json" 2>/dev/null
"${prism[@]}" -q -t 0.15 -n 4 --hold-retries --json "$dir/a.stl" "$dir/h1.vmsh" >"$dir/h1.json" 2>/dev/null
rc=$?
held=$(grep -o '"held_steps": [0-9]*' "$dir/h1.json" | awk '{print $2}')
check '[ $rc -eq 0 ] && [ "${held:-0}" -gt 0 ] && grep -q "\"valid\": true" "$dir/h1.json" && grep -q "\"intersecting_pairs\": 0," "$dir/h1.json" && grep -q "\"held_steps\": 0," "$dir/h0.json"' \
  "--hold-retries at T = 15 %: $held held steps, valid (got $rc; without: $(grep -o '"held_steps": [0-9]*' "$dir/h0.json"))"
echo "  thickness mean without / with: $(grep -o '"thickness_mean": [0-9.e+-]*' "$dir/h0.json" | awk '{print $2}') / $(grep -o '"thickness_mean": [0-9.e+-]*' "$dir/h1.json" | awk '{print $2}')"
check 'grep -q "^springback" "$dir/a.err"' "progress on stderr"
# a solve's iterations carry their functional F, marching's splits their
# layer heights (marching's solves used to print F under "height": values
# far above the thickness)
T=$(grep -o "thickness [0-9.e+-]*" "$dir/a.err" | head -1 | awk '{print $2}')
check 'grep -Eq "^springback +10  F +[0-9.e+-]+ " "$dir/a.err" && grep -Eq "^march +1  height " "$dir/a.err" && awk -v T="$T" "\$1 == \"march\" && \$3 == \"height\" && !(\$4 > 0 && \$4 <= T) { bad = 1 } END { exit bad }" "$dir/a.err"' "progress: F for solves, heights within T ($T) for marching's layers"
check 'grep -q "^\$MeshFormat" "$dir/a.msh" && sed -n 2p "$dir/a.msh" | grep -q "^4.1 0 8"' ".msh is Gmsh 4.1"
check 'grep -q "\"wall\"" "$dir/a.msh" && grep -q "\"outer\"" "$dir/a.msh"' ".msh names the wall and outer families"
# the default 20 layers: every smooth column's first side edge within 5
# degrees of the wall normal, also those beside the wing and tail junctions
# whose neighbours stay tilted (they bend back over up to 19 layers)
"${prism[@]}" -q -t 0.05 --json "$dir/a.stl" "$dir/a20.vmsh" >"$dir/a20.json" 2>"$dir/a20.err"
check '[ $? -eq 0 ] && grep -q "\"layers\": 20," "$dir/a20.json"' "20 layers on the aircraft"
check 'grep -q "\"normal_dev_over_5deg\": 0," "$dir/a20.json"' "20 layers: no smooth column's first layer beyond 5 degrees ($(grep -o '"normal_dev_over_5deg": [0-9]*' "$dir/a20.json"))"
# the cost figures: the marching's eight steps add up to its phase's time
# (the layer ends after them take the rest), the peak memory never falls
# from one phase to the next and the run's is the largest
mt=$(grep -o '"march_time": {[^}]*}' "$dir/a20.json")
pk=$(grep -o '"peak_mb": {[^}]*}' "$dir/a20.json")
march=$(grep -o '"march": [0-9.]*' "$dir/a20.json" | head -1 | awk '{print $2}')
check 'echo "$mt" | grep -o "[0-9.]*[,}]" | tr -d ",}" | awk -v m="$march" "{ s += \$1; n++ } END { exit !(n == 8 && s <= m + 0.01 && s >= 0.9 * m) }"' "--json: the marching's 8 steps add up to its $march s ($mt)"
check 'echo "$pk" | grep -o "[0-9.]*[,}]" | tr -d ",}" | awk "{ if (\$1 <= 0 || \$1 < p) bad = 1; p = \$1; n++ } END { exit bad || n != 6 }"' "--json: the peak memory per phase, positive and never falling ($pk)"
"$qual" --json "$dir/a.msh" >"$dir/q.json" 2>/dev/null
check 'grep -q "\"prism\": {\"elements\": 11960" "$dir/q.json"' "vm-quality reads 11,960 prisms back"
"$qual" --verify "$dir/a.msh" >"$dir/v.log" 2>&1
check '[ $? -eq 0 ] && grep -q "outer faces intersect neither each other nor the wall" "$dir/v.log"' "vm-quality --verify (CGAL, exact): positive corner tets, no intersection"
if command -v gmsh >/dev/null 2>&1; then
  gmsh -check "$dir/a.msh" >"$dir/gmsh.log" 2>&1
  check '[ $? -eq 0 ] && ! grep -qi "error" "$dir/gmsh.log"' "gmsh -check accepts the .msh"
else
  echo "skip: gmsh not installed"
fi
for f in vtu vmsh su2; do
  "${prism[@]}" -q -t 0.05 -n 2 "$dir/a.stl" "$dir/b.$f"
  check '[ $? -eq 0 ] && [ -s "$dir/b.$f" ]' "writes .$f"
done
check 'grep -q "^NELEM= 5980" "$dir/b.su2" && grep -q "^NMARK= 2" "$dir/b.su2" && grep -q "^MARKER_TAG= wall" "$dir/b.su2"' ".su2 has the cells and the wall and outer markers"
# SU2 numbers a prism like VTK's wedge: the base (0,1,2) has its normal
# pointing away from the top face (3,4,5); count the prisms that do not
awk '/^NELEM=/ {ne = $2; next}
     /^NPOIN=/ {np = $2; ip = 0; next}
     ne > 0 && $1 == 13 && !np {n++; for (k = 0; k < 6; k++) c[n, k] = $(k + 2); next}
     np && ip < np {x[ip] = $1; y[ip] = $2; z[ip] = $3; ip++}
     END {
       bad = 0
       for (i = 1; i <= n; i++) {
         a0 = c[i, 0]; a1 = c[i, 1]; a2 = c[i, 2]
         ux = x[a1] - x[a0]; uy = y[a1] - y[a0]; uz = z[a1] - z[a0]
         vx = x[a2] - x[a0]; vy = y[a2] - y[a0]; vz = z[a2] - z[a0]
         nx = uy * vz - uz * vy; ny = uz * vx - ux * vz; nz = ux * vy - uy * vx
         tx = (x[c[i, 3]] + x[c[i, 4]] + x[c[i, 5]]) / 3 - x[a0]
         ty = (y[c[i, 3]] + y[c[i, 4]] + y[c[i, 5]]) / 3 - y[a0]
         tz = (z[c[i, 3]] + z[c[i, 4]] + z[c[i, 5]]) / 3 - z[a0]
         if (nx * tx + ny * ty + nz * tz >= 0) bad++
       }
       print n, bad
     }' "$dir/b.su2" >"$dir/su2.orient"
check '[ "$(cat "$dir/su2.orient")" = "5980 0" ]' ".su2 prisms in VTK's wedge order (base normal away from the top): $(cat "$dir/su2.orient") (prisms, wrong)"
"${prism[@]}" -q -t 0.05 -n 2 "$dir/a.stl" "$dir/b.cgns" 2>"$dir/cg.err"
rc=$?
if [ $rc -eq 0 ]; then
  check '[ "$(head -c 4 "$dir/b.cgns" | od -An -c | tr -d " ")" = "211HDF" ]' ".cgns is an HDF5 file"
else
  check '[ $rc -eq 2 ] && grep -q "no CGNS support" "$dir/cg.err" && [ ! -e "$dir/b.cgns" ]' "without libcgns: usage error, no file"
fi

# bad input: one line on stderr, exit 1, no output file
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n' >"$dir/bad.stl"
"${prism[@]}" "$dir/bad.stl" "$dir/bad.msh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ "$(wc -l <"$dir/err")" -eq 1 ] && [ ! -e "$dir/bad.msh" ]' "truncated STL: exit 1, one line, no output"
"${prism[@]}" "$dir/none.stl" "$dir/none.msh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ "$(wc -l <"$dir/err")" -eq 1 ] && [ ! -e "$dir/none.msh" ]' "missing input: exit 1, one line, no output"
# an open wall (one triangle): refused before any work
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n' >"$dir/one.stl"
"${prism[@]}" -q "$dir/one.stl" "$dir/one.msh" 2>"$dir/err"
rc=$?
check '[ $rc -ne 0 ] && [ "$(wc -l <"$dir/err")" -eq 1 ] && [ ! -e "$dir/one.msh" ]' "open wall: non-zero exit ($rc), one line, no output"
# usage errors: exit 2
"${prism[@]}" -T -1 "$dir/a.stl" "$dir/u.msh" 2>/dev/null
check '[ $? -eq 2 ] && [ ! -e "$dir/u.msh" ]' "negative thickness: exit 2"
"${prism[@]}" -n 0 "$dir/a.stl" "$dir/u.msh" 2>/dev/null
check '[ $? -eq 2 ] && [ ! -e "$dir/u.msh" ]' "zero layers: exit 2"
# a wall oriented inwards (every facet's vertices in reverse order) is
# turned with a warning and the layer grows outside; --no-orient refuses it
"$gen" sphere --level 2 "$dir/s.stl" >/dev/null
awk '/^ *vertex/ { v[++n] = $0; if (n == 3) { print v[1]; print v[3]; print v[2]; n = 0 }; next } { print }' "$dir/s.stl" >"$dir/inv.stl"
"${prism[@]}" -n 3 --json "$dir/inv.stl" "$dir/inv.vmsh" >"$dir/inv.json" 2>"$dir/inv.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"reoriented\": true" "$dir/inv.json" && grep -q "\"valid\": true" "$dir/inv.json" && awk -F"\"thickness_min\": " "{ split(\$2, a, \",\"); exit !(a[1] > 0.99) }" "$dir/inv.json" && grep -q "oriented inwards.*turned" "$dir/inv.err"' "inward wall: turned with a warning, the layer outside at full thickness (exit $rc)"
"${prism[@]}" -n 3 --json "$dir/s.stl" "$dir/out.vmsh" >"$dir/out.json" 2>/dev/null
check 'grep -q "\"reoriented\": false" "$dir/out.json"' "outward wall: not turned"
"${prism[@]}" -q -n 3 --no-orient "$dir/inv.stl" "$dir/inv2.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ "$(wc -l <"$dir/err")" -eq 1 ] && grep -q "oriented inwards" "$dir/err" && [ ! -e "$dir/inv2.vmsh" ]' "--no-orient: an inward wall is refused, exit 1, one line, no output"
"${prism[@]}" "$dir/a.stl" "$dir/u.xyz" 2>/dev/null
check '[ $? -eq 2 ] && [ ! -e "$dir/u.xyz" ]' "unknown output format: exit 2"
"${prism[@]}" --first-height 5 -T 1 "$dir/a.stl" "$dir/u.msh" 2>/dev/null
check '[ $? -eq 2 ] && [ ! -e "$dir/u.msh" ]' "first height above the thickness: exit 2"
# needles (triangles under 1 degree): the wing vm-gen makes as a CAD
# mesher grades it has rows of them, the sphere none. By default such a
# wall goes through the surface stage first (said, "surface_stage" and
# "needles_in" in the JSON, none left); --keep-wall extrudes it as it is,
# with a warning giving the count
"${prism[@]}" -q --json --time-limit 0.01 "$dir/w.stl" "$dir/ws.vmsh" >"$dir/ws.json" 2>"$dir/ws.err"
nin=$(sed -n 's/.*"needles_in": \([0-9]*\).*/\1/p' "$dir/ws.json")
check '[ "${nin:-0}" -gt 1000 ] && grep -q "\"surface_stage\": true, \"needles\": 0," "$dir/ws.json" && grep -q "$nin triangles under 1 degree.*goes through the surface stage first" "$dir/ws.err"' \
  "wing: $nin needles, the surface stage run and said, none left: $(grep -o 'the wall goes through the surface stage first' "$dir/ws.err")"
"${prism[@]}" -q --json --keep-wall --time-limit 0.01 "$dir/w.stl" "$dir/wk.vmsh" >"$dir/wk.json" 2>"$dir/wk.err"
nn=$(sed -n 's/.*"needles": \([0-9]*\).*/\1/p' "$dir/wk.json")
check '[ "${nn:-0}" -eq "${nin:-1}" ] && grep -q "\"surface_stage\": false" "$dir/wk.json" && grep -q "$nn triangles under 1 degree.*--keep-wall extrudes the wall as it is" "$dir/wk.err"' \
  "wing, --keep-wall: $nn needles extruded, warned"
# an open wall with a needle: the surface stage refuses it, and the error
# does not send the user to --keep-wall (the layer needs a closed wall)
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0.5 0.001 0\nendloop\nendfacet\nendsolid x\n' >"$dir/needle.stl"
"${prism[@]}" -q "$dir/needle.stl" "$dir/needle.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ "$(grep -c "error:" "$dir/err")" -eq 1 ] && grep -q "error: .*the surface stage: open surface.*(the layer needs a closed wall)$" "$dir/err" && [ ! -e "$dir/needle.vmsh" ]' \
  "an open wall with a needle: exit 1, one error line, no output (got $rc: $(grep error: "$dir/err"))"
check 'grep -q "\"needles_in\": 0, \"surface_stage\": false, \"needles\": 0" "$dir/out.json" && ! grep -q "under 1 degree" "$dir/inv.err"' "sphere: no needles, no surface stage, no warning"
exit $fail
