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

# impossible: a fixed inverted hex (every vertex fixed by the 'fixed' field)
cat >"$dir/bad.vtk" <<'VTK'
# vtk DataFile Version 3.0
inverted hex, every vertex fixed
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 8 double
0 0 0 1 0 0 1 1 0 0 1 0
0 0 -1 1 0 -1 1 1 -1 0 1 -1
CELLS 1 9
8 0 1 2 3 4 5 6 7
CELL_TYPES 1
12
POINT_DATA 8
SCALARS fixed int 1
LOOKUP_TABLE default
1 1 1 1 1 1 1 1
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
check '[ -z "$(ls "$dir" | grep -i tmp)" ]' "no temporary files left after the interruptions"
exit $fail
