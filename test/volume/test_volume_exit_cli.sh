#!/usr/bin/env bash
# test/volume/test_volume_exit_cli.sh: vm-volume on input it cannot repair:
# an inverted hex whose vertices are all fixed ends at once with exit 3,
# naming the element and --slip-boundary, the input written; vm-quality
# --require-valid and --verify refuse a mesh whose corner tets are all
# positive but whose hex is not certified (det J < 0 inside); fixed
# vertices outside the fixed (or sliding) boundary end at once too; an
# untangling that stalls for good is stopped, exit 3.
set -u
vol=$1 qual=$2 gen=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; else echo "ok: $2"; fi; }

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
"$vol" --time-limit 60 "$dir/bad.vtk" "$dir/bad_out.vtk" 2>"$dir/bad.err"
rc=$?
took=$(($(date +%s) - start))
check '[ $rc -eq 3 ]' "an inverted hex with only fixed vertices: exit 3 (got $rc)"
check '[ $took -le 2 ]' "at once, not at the time limit (took $took s)"
check 'grep -q "element 0 (hex) is inverted and all its vertices are fixed" "$dir/bad.err" &&
  grep -q -- "--slip-boundary" "$dir/bad.err"' "naming the element and the option that helps"
check '! grep -q "^[a-z]*  *it  *[0-9]" "$dir/bad.err"' "without running the schedule"
check '[ -s "$dir/bad_out.vtk" ]' \
  "the input is written to OUT"
"$qual" -q "$dir/bad_out.vtk" >/dev/null
check '[ $? -eq 0 ]' "and it is readable"

# the rotated cube's inner cube turned through the outer one: 3pi/4 about
# z with half-size 0.45 puts its corners at 0.566 > 0.5 (204 fixed
# vertices outside); about (1,1,1) fewer poke out (18); a free boundary may
# still try
"$gen" rotcube --n 20 --angle 3pi/4 --inner 0.45 "$dir/out.vmsh"
"$gen" rotcube --n 20 --angle 3pi/4 --inner 0.45 --axis 1,1,1 "$dir/out111.vmsh"
"$gen" rotcube --n 20 --angle 3pi/4 --inner 0.4 "$dir/in04.vmsh"
start=$(date +%s)
"$vol" --time-limit 60 "$dir/out.vmsh" "$dir/out_res.vmsh" 2>"$dir/out.err"
rc=$?
took=$(($(date +%s) - start))
check '[ $rc -eq 3 ] && [ $took -le 2 ]' "fixed vertices outside the boundary: exit 3 at once (got $rc after $took s)"
check 'grep -q "error: .*out.vmsh: fixed vertex [0-9]* at (0.565685, .*) lies outside the fixed boundary (204 such vertices).*--free-boundary" "$dir/out.err"' \
  "naming a vertex, where it is, how many and the option that helps"
check 'cmp -s "$dir/out.vmsh" "$dir/out_res.vmsh"' "the input written unchanged"
"$vol" --time-limit 60 --slip-boundary "$dir/out111.vmsh" "$dir/out_res.vmsh" 2>"$dir/out111.err"
rc=$?
check '[ $rc -eq 3 ] && grep -q "lies outside the sliding boundary (18 such vertices)" "$dir/out111.err"' \
  "about (1,1,1), with a sliding boundary: the same (got $rc)"
"$vol" --time-limit 1 -q --free-boundary "$dir/out.vmsh" "$dir/out_res.vmsh" 2>"$dir/free.err"
check '! grep -q "lies outside" "$dir/free.err"' "a free boundary is not refused"
"$vol" --time-limit 1 -q "$dir/in04.vmsh" "$dir/out_res.vmsh" 2>"$dir/in04.err"
check '! grep -q "lies outside" "$dir/in04.err"' \
  "half-size 0.4: the turned fixed vertices stay inside (0.495 < 0.5), not refused"
"$gen" rotcube --n 16 --angle pi/4 --inner 0.3 "$dir/graze.vmsh"
"$vol" --time-limit 1 -q "$dir/graze.vmsh" "$dir/out_res.vmsh" 2>"$dir/graze.err"
check '! grep -q "lies outside" "$dir/graze.err"' \
  "n = 16, pi/4, half-size 0.3: inside, not refused (rays from its turned vertices along simple irrational directions grazed the outer grid's edges)"

# a cube it cannot untangle, with no proof that it cannot: n = 6, pi about
# (0,1,1), inner half-size 0.3 (one cell of shell around the turned inner
# cube). Foldover's eps collapses to 1e-11 at min det -0.88 and nothing
# moves: the run is stopped as stalled (2-4 s) instead of spending the
# iteration budget (15,221 untangling iterations, 17 s, before the stall
# watch); exit 3, the best state written, the JSON says so
"$gen" rotcube --n 6 --angle pi --axis 0,1,1 --inner 0.3 "$dir/stall.vmsh"
"$vol" --threads 1 --time-limit 60 --json "$dir/stall.vmsh" "$dir/stall_out.vmsh" \
  >"$dir/stall.json" 2>"$dir/stall.err"
rc=$?
iters=$(sed -n 's/.*"iter_untangle": \([0-9]*\).*/\1/p' "$dir/stall.json")
check '[ $rc -eq 3 ] && grep -q "\"stalled\": true" "$dir/stall.json"' \
  "a cube it cannot untangle: exit 3, \"stalled\" in the JSON (got $rc)"
check '[ -n "$iters" ] && [ "$iters" -lt 5000 ]' \
  "stopped after $iters untangling iterations, not at the budget"
check 'grep -q "untangling was stopped as stalled: its eps had fallen to 1e-11 and 300 iterations" "$dir/stall.err" &&
  grep -q "not valid: .*the best state is written" "$dir/stall.err" && [ -s "$dir/stall_out.vmsh" ]' \
  "saying so, and the best state written"
"$gen" rotcube --n 8 --angle pi/2 "$dir/ok.vmsh"
"$vol" --threads 1 --json "$dir/ok.vmsh" "$dir/ok_out.vmsh" >"$dir/ok.json" 2>/dev/null
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"stalled\": false" "$dir/ok.json"' \
  "a cube it can untangle: exit 0, not stalled (got $rc)"

# hex 283 of the n = 16 pi cube after the staged schedule without the
# repair (scaled): all 8 corner tets positive, det J < 0 inside
cat >"$dir/twist.vtk" <<'VTK'
# vtk DataFile Version 3.0
hex 283 of the staged pi cube
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 8 double
0.702733597193 0.241228872106 0.468642832906
0.801246873827 0.235344946219 0.475276787726
0.808961367894 0.423207519118 0.452931594278
0.693504234923 0.413552081061 0.466727544172
0.283264592531 0.417974666146 0.484960760253
0.212336243335 0.476328221958 0.512317124808
0.195577585156 0.792363693392 0.564984447686
0.302375505141 1 0.574158908171
CELLS 1 9
8 0 1 2 3 4 5 6 7
CELL_TYPES 1
12
VTK
"$qual" --json "$dir/twist.vtk" >"$dir/twist.json" 2>/dev/null
corner_ok=$(grep -c '"all": {[^}]*"M": 0' "$dir/twist.json")
"$qual" -q --require-valid "$dir/twist.vtk" >/dev/null 2>"$dir/twist.err"
rc=$?
if [ "$corner_ok" -eq 1 ]; then
  check '[ $rc -eq 3 ] && grep -q "not certified valid" "$dir/twist.err"' \
    "corner tets positive, det J < 0 inside: --require-valid exits 3 (got $rc)"
  "$qual" -q --verify "$dir/twist.vtk" >/dev/null 2>"$dir/twist2.err"
  rc=$?
  check '[ $rc -eq 3 ] && grep -q "is not certified valid" "$dir/twist2.err"' \
    "and --verify exits 3 naming the element (got $rc)"
else
  check 'false' "the hex has positive corner tets (test set-up)"
fi
exit $fail
