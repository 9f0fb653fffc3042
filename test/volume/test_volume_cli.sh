#!/usr/bin/env bash
# test/volume/test_volume_cli.sh: vm-volume end to end: a tangled .vtk with a
# 'fixed' point array in, a valid .vtk out (exit 0); an impossible problem
# gives exit 3 with the best mesh written; bad input gives exit 1 and no
# output; usage errors exit 2.
set -u
gen=$1 vol=$2 qual=$3 conv=$4
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; else echo "ok: $2"; fi; }

"$gen" rotcube --n 8 --angle pi/2 "$dir/in.vtk"
check 'grep -q "fixed" "$dir/in.vtk"' "the generated file carries a fixed point array"
"$qual" --require-valid "$dir/in.vtk" >/dev/null 2>&1
check '[ $? -eq 3 ]' "the input is tangled (vm-quality --require-valid exits 3)"
"$vol" --json "$dir/in.vtk" "$dir/out.vtk" >"$dir/sum.json" 2>"$dir/err.txt"
rc=$?
check '[ $rc -eq 0 ]' "vm-volume exits 0 on the pi/2 cube (got $rc)"
check 'grep -q "\"valid\": true" "$dir/sum.json"' "JSON summary says valid"
check 'grep -q "^[a-z]*  *it  *[0-9]" "$dir/err.txt"' "progress lines on stderr"
check 'grep -q "\"verified\": true" "$dir/sum.json"' "the exact check (as vm-quality --verify) ran"
check 'grep -q "verify: every quadrature simplex (corner rule) positively oriented (exact)" \
  "$dir/err.txt"' "and said so on stderr"
"$qual" --require-valid "$dir/out.vtk" >/dev/null
check '[ $? -eq 0 ]' "the output is valid by vm-quality"
check '[ ! -e "$dir/out.vtk.tmp"* ] 2>/dev/null; true' "no temporary files left"

# a mesh without hexahedra: the direct schedule by foldover by default (the
# 6-tet split of the n = 12 cube turned 3pi/4, inner 0.3: certified after 27
# untangling + 187 local iterations, where the adaptive penalty, the default
# before, stalled at its 5,000 and needed the foldover fallback: 26 + 5,190);
# when it stalls (here forced: --max-iter 8 leaves it 2 iterations) the
# adaptive penalty goes on
"$gen" rotcube --n 12 --angle 3pi/4 --inner 0.3 --tets "$dir/tets.vmsh"
"$vol" --json "$dir/tets.vmsh" "$dir/tets-out.vmsh" >"$dir/tets.json" 2>"$dir/tets.err"
rc=$?
check '[ $rc -eq 0 ]' "vm-volume exits 0 on the 6-tet split, 3pi/4 (got $rc)"
check 'grep -q "\"method\": \"foldover\"" "$dir/tets.json" && grep -q "\"staged\": false" "$dir/tets.json" &&
  grep -q "\"fallback\": false" "$dir/tets.json" && grep -q "\"valid\": true" "$dir/tets.json"' \
  "JSON: direct, foldover, no fallback, valid"
iters=$(python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d["iter_untangle"] + d["iter_local"])' "$dir/tets.json")
check '[ "$iters" -le 400 ]' "untangled within 400 iterations (got $iters)"
"$vol" --max-iter 8 --json "$dir/tets.vmsh" "$dir/tets-fb.vmsh" >"$dir/fb.json" 2>"$dir/fb.err"
rc=$?
check '[ $rc -eq 3 ]' "a run out of iterations exits 3 (got $rc)"
check 'grep -q "the direct schedule stalled with [0-9]* inverted nodes left; going on from its best state with the direct schedule (adaptive)" "$dir/fb.err" &&
  grep -q "\"fallback\": true" "$dir/fb.json" && grep -q "\"method\": \"adaptive\"" "$dir/fb.json"' \
  "a stalled direct run falls back to the adaptive penalty and says so"

# --staged on the pi-rotated cube (n = 16: two free layers between the fixed
# boundary and the fixed inner cube), which the default schedule leaves
# tangled: the 6-tet split, then the corners with the split held valid
"$gen" rotcube --n 16 --angle pi "$dir/pi.vtk"
"$vol" --staged --threads 2 --progress-every 20 --json "$dir/pi.vtk" "$dir/pi-out.vtk" \
  >"$dir/pi.json" 2>"$dir/pi.err"
rc=$?
check '[ $rc -eq 0 ]' "vm-volume --staged exits 0 on the pi cube, n = 16 (got $rc)"
check 'grep -q "\"staged\": true" "$dir/pi.json" && grep -q "\"split_valid\": true" "$dir/pi.json" &&
  grep -q "\"method\": \"foldover\"" "$dir/pi.json"' "JSON: staged, split untangled, foldover implied"
check 'grep -q "^split  *it" "$dir/pi.err" && grep -q "^guarded  *it" "$dir/pi.err" &&
  grep -q "^optimize  *it" "$dir/pi.err"' "progress lines of the split, guarded and optimize phases"
check 'grep -q "staged: the 6-tet split.s M 1720 .* untangled after" "$dir/pi.err"' \
  "the split's own count is reported"
"$qual" --require-valid "$dir/pi-out.vtk" >/dev/null
check '[ $? -eq 0 ]' "the staged output is valid by vm-quality"

# --slip-boundary: the boundary slides on the cube's faces and edges; the
# corners and the inner cube stay; the file's fields pass through
"$gen" rotcube --n 8 --angle pi/2 --free-boundary "$dir/slip.vtk"
"$vol" --slip-boundary --json "$dir/slip.vtk" "$dir/slip-out.vtk" >"$dir/slip.json" 2>"$dir/slip.err"
rc=$?
check '[ $rc -eq 0 ]' "vm-volume --slip-boundary exits 0 (got $rc)"
check 'grep -q "slip boundary: 386 boundary vertices: 294 slide on the surface, 84 along 12 sharp edge lines, 8 corners" "$dir/slip.err"' \
  "slip classes: 6x7x7 face, 12x7 edge vertices, 8 corners"
check 'grep -q "\"slip_max_distance\": 0" "$dir/slip.json" || grep -q "\"slip_max_distance\": [0-9.]*e-1[0-9]" "$dir/slip.json"' \
  "boundary vertices stay on the boundary surface"
"$vol" --slip-boundary --free-boundary "$dir/slip.vtk" "$dir/x.vtk" 2>/dev/null
check '[ $? -eq 2 ]' "--slip-boundary with --free-boundary is a usage error"
check 'grep -q "\"boundary_moved\": false" "$dir/slip.json" && grep -q "\"flat_elements\": 0" "$dir/slip.json"' \
  "a slip run keeps the shape and leaves no flat element"

# a boundary folded by tangled boundary hexes (the SOS-hex bunny's case):
# the unit cube, n = 6, with a top-face vertex pushed in x past its
# neighbour (the quads there fold over) and a vertex of the edge y = 0,
# z = 1 pushed along that edge past its neighbour. The folds' edges and the
# edge's turn back are not features, so those vertices slide back; before,
# they made 16 feature lines and 16 corners (fixed) and the run stalled.
fold_cube() { # $1: output
  awk -v n=6 'BEGIN {
    N = (n + 1) ^ 3
    print "# vtk DataFile Version 3.0"; print "folded cube"; print "ASCII"
    print "DATASET UNSTRUCTURED_GRID"; print "POINTS " N " double"
    for (k = 0; k <= n; k++) for (j = 0; j <= n; j++) for (i = 0; i <= n; i++) {
      x = i / n; y = j / n; z = k / n
      if (k == n && j == n / 2 && i == n / 2) x += 1.6 / n
      if (k == n && j == 0 && i == 2) x += 1.6 / n
      printf "%.17g %.17g %.17g\n", x, y, z
    }
    print "CELLS " n ^ 3 " " 9 * n ^ 3
    for (k = 0; k < n; k++) for (j = 0; j < n; j++) for (i = 0; i < n; i++) {
      a = k * (n + 1) ^ 2 + j * (n + 1) + i; b = a + (n + 1) ^ 2
      print 8, a, a + 1, a + n + 2, a + n + 1, b, b + 1, b + n + 2, b + n + 1
    }
    print "CELL_TYPES " n ^ 3
    for (c = 0; c < n ^ 3; c++) print 12
  }' >"$1"
}
fold_cube "$dir/fold.vtk"
"$qual" --require-valid "$dir/fold.vtk" >/dev/null 2>&1
check '[ $? -eq 3 ]' "the folded cube is tangled"
"$vol" --slip-boundary --time-limit 60 --json "$dir/fold.vtk" "$dir/fold-out.vtk" >"$dir/fold.json" 2>"$dir/fold.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/fold.json" && grep -q "\"boundary_moved\": false" "$dir/fold.json"' \
  "--slip-boundary unfolds a folded boundary, the shape kept (got $rc)"
check 'grep -q "slip boundary: 218 boundary vertices: .* along 12 sharp edge lines, 8 corners" "$dir/fold.err" &&
  grep -q "sharp edges and line turns where the input.s boundary folds back" "$dir/fold.err"' \
  "the cube's own 12 lines and 8 corners, the folds said and left out"

# a free or sliding boundary that does not keep the shape fails (exit 3,
# the mesh written): the 3pi/4 cube with a free boundary turns as a whole
# with its fixed inner cube (every cell valid, the corners 0.2 away: 0.207,
# 0.213 with the staged schedule's quasi-isometric step since session 60)
"$gen" rotcube --n 6 --angle 3pi/4 --free-boundary "$dir/turn.vtk"
"$vol" --free-boundary --json "$dir/turn.vtk" "$dir/turn-out.vtk" >"$dir/turn.json" 2>"$dir/turn.err"
rc=$?
check '[ $rc -eq 3 ] && [ -s "$dir/turn-out.vtk" ] && grep -q "\"valid\": false" "$dir/turn.json" &&
  grep -q "\"boundary_moved\": true" "$dir/turn.json" && grep -q "\"certified_invalid\": 0, \"certified_undecided\": 0" "$dir/turn.json"' \
  "--free-boundary that turns the shape: exit 3, valid cells, the shape not kept (got $rc)"
check 'grep -q "error: .*turn-out.vtk: the boundary moved by 2\.[0-9]*e-01 .*1[0-9.]* % of its diagonal, beyond --boundary-tolerance 0.01.*--slip-boundary" "$dir/turn.err"' \
  "one line: how far, where, the tolerance, the option that keeps it"
"$vol" --free-boundary --boundary-tolerance 0.5 "$dir/turn.vtk" "$dir/turn-out.vtk" 2>"$dir/turn2.err"
check '[ $? -eq 0 ] && grep -q "boundary moved by at most 2\.[0-9]*e-01" "$dir/turn2.err"' \
  "within a tolerance the user gives, the same run exits 0 and says how far it moved"
# sliding without features: the cube's edges and corners are rounded off
"$vol" --slip-boundary --feature-angle 179 --max-iter 2000 --json "$dir/slip.vtk" "$dir/round.vtk" >"$dir/round.json" 2>"$dir/round.err"
rc=$?
check '[ $rc -eq 3 ] && grep -q "\"boundary_moved\": true" "$dir/round.json" && grep -q "smaller --feature-angle" "$dir/round.err"' \
  "a slide across the cube's unmarked edges fails, naming --feature-angle (got $rc)"
# flat elements: the threshold is the user's; cells whose vertices are all
# fixed (the inner cube's) are not the stage's to answer for
"$vol" --slip-boundary --min-sj 0.5 --json "$dir/slip.vtk" "$dir/flat.vtk" >"$dir/flat.json" 2>"$dir/flat.err"
rc=$?
nflat=$(sed -n 's/.*"flat_elements": \([0-9]*\).*/\1/p' "$dir/flat.json")
check '[ $rc -eq 3 ] && [ "${nflat:-0}" -gt 0 ] && [ "$nflat" -lt 512 ] && grep -q "elements are flat (scaled Jacobian below --min-sj 0.5): the worst, element [0-9]* near (" "$dir/flat.err"' \
  "elements below --min-sj fail the run, the worst one named ($nflat flat, rc $rc)"

# impossible: a fixed inverted hex (every vertex fixed by the 'fixed' field)
cat >"$dir/bad.vtk" <<'VTK'
# vtk DataFile Version 3.0
an inverted hex beside a valid one (the total volume positive: not a mesh numbered the other way round), every vertex fixed
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 16 double
0 0 0 1 0 0 1 1 0 0 1 0
0 0 -1 1 0 -1 1 1 -1 0 1 -1
3 0 0 5 0 0 5 1 0 3 1 0
3 0 1 5 0 1 5 1 1 3 1 1
CELLS 2 18
8 0 1 2 3 4 5 6 7
8 8 9 10 11 12 13 14 15
CELL_TYPES 2
12
12
POINT_DATA 16
SCALARS fixed int 1
LOOKUP_TABLE default
1 1 1 1 1 1 1 1 1 1 1 1 1 1 1 1
VTK
start=$(date +%s)
"$vol" --time-limit 20 "$dir/bad.vtk" "$dir/bad_out.vtk" 2>"$dir/bad.err"
rc=$?
took=$(($(date +%s) - start))
check '[ $rc -eq 3 ]' "an impossible problem exits 3 (got $rc)"
check '[ $took -le 2 ]' "at once, not at the time limit (took $took s)"
check 'grep -q "element 0 (hex) is inverted and all its vertices are fixed" "$dir/bad.err" &&
  grep -q -- "--slip-boundary" "$dir/bad.err"' "naming the element and the option that helps"
check '[ ! -s "$dir/bad.err" ] || ! grep -q "^untangle\|^split" "$dir/bad.err"' "without running the schedule"
check '[ -s "$dir/bad_out.vtk" ]' "and still writes the best mesh"

printf 'not a mesh\n' >"$dir/garbage.vtk"
"$vol" -q "$dir/garbage.vtk" "$dir/g_out.vtk" 2>"$dir/gerr.txt"
rc=$?
check '[ $rc -eq 1 ]' "bad input exits 1 (got $rc)"
check '[ $(wc -l <"$dir/gerr.txt") -eq 1 ]' "with a one-line error"
check '[ ! -e "$dir/g_out.vtk" ]' "and no output file"
"$vol" --no-such-option "$dir/in.vtk" "$dir/x.vtk" 2>/dev/null
check '[ $? -eq 2 ]' "usage errors exit 2"

# interruption: a long run (pi at n = 16 does not finish quickly) stopped by
# SIGINT writes its best state and exits 4; two SIGINTs exit at once and
# leave the output alone
"$gen" rotcube --n 16 --angle pi "$dir/long.vmsh"
echo "previous content" >"$dir/long_out2.vmsh"
"$vol" -q --threads 1 "$dir/long.vmsh" "$dir/long_out.vmsh" &
pid=$!
sleep 3
kill -INT $pid
wait $pid
rc=$?
check '[ $rc -eq 4 ]' "SIGINT: exit 4 (got $rc)"
check '[ -s "$dir/long_out.vmsh" ]' "SIGINT: the best state is written"
"$qual" -q "$dir/long_out.vmsh" >/dev/null
check '[ $? -eq 0 ]' "SIGINT: the written mesh is readable"
"$vol" -q --threads 1 "$dir/long.vmsh" "$dir/long_out2.vmsh" &
pid=$!
sleep 3
# identical pending signals merge into one, so queue two different ones
# while the process is stopped: both handlers run, the second exits at once
kill -STOP $pid; kill -TERM $pid; kill -INT $pid; kill -CONT $pid
wait $pid
rc=$?
check '[ $rc -eq 130 ] || [ $rc -eq 143 ]' "two signals: exit at once with 128+signal (got $rc)"
check '[ "$(cat "$dir/long_out2.vmsh")" = "previous content" ]' "two signals: the output is untouched"
"$vol" -q --threads 1 "$dir/long.vmsh" "$dir/long_out3.vmsh" &
pid=$!
sleep 3
kill -TERM $pid
wait $pid
rc=$?
check '[ $rc -eq 4 ] && [ -s "$dir/long_out3.vmsh" ]' "SIGTERM: exit 4, best state written (got $rc)"
# the time limit: the same distinct exit, the best state written atomically
"$vol" --json --threads 1 --time-limit 2 "$dir/long.vmsh" "$dir/long_out4.vmsh" \
  >"$dir/tl.json" 2>"$dir/tl.err"
rc=$?
check '[ $rc -eq 4 ] && [ -s "$dir/long_out4.vmsh" ]' "--time-limit: exit 4, best state written (got $rc)"
check 'grep -q "\"timed_out\": true" "$dir/tl.json" && grep -q "time limit reached" "$dir/tl.err"' \
  "--time-limit: said in the JSON and on stderr"
# the time limit running out after the mesh is certified valid (a cube turned
# so little that it starts valid; n = 24: the optimization takes longer than
# the limit): a success, said on stderr and in the JSON
"$gen" rotcube --n 24 --angle pi/32 "$dir/calm.vmsh"
"$vol" --json --threads 1 --time-limit 0.5 "$dir/calm.vmsh" "$dir/calm_out.vmsh" \
  >"$dir/calm.json" 2>"$dir/calm.err"
rc=$?
check '[ $rc -eq 0 ] && [ -s "$dir/calm_out.vmsh" ]' "--time-limit after certification: exit 0 (got $rc: $(tail -2 "$dir/calm.err"))"
check 'grep -q "\"timed_out\": true" "$dir/calm.json" && grep -q "\"valid\": true" "$dir/calm.json" && grep -q "the time limit was reached after the mesh was certified valid" "$dir/calm.err"' \
  "--time-limit after certification: timed_out and valid in the JSON, said on stderr"
"$qual" --verify "$dir/calm_out.vmsh" >/dev/null 2>&1
check '[ $? -eq 0 ]' "--time-limit after certification: vm-quality --verify accepts the mesh"
check '[ -z "$(ls "$dir" | grep -i tmp)" ]' "no temporary files left after the interruptions"
exit $fail
