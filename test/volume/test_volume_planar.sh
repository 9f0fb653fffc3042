#!/usr/bin/env bash
# test/volume/test_volume_planar.sh: vm-volume on planar 2D meshes (tangled
# quads and triangles in z = 0, z = 5, y = 0.25 and a tilted plane, ordered
# counter-clockwise or clockwise): untangled and certified, written back in
# their plane with the fixed vertices bit for bit, vm-quality agreeing; and
# what it refuses: a vertex off the plane, elements not oriented alike, a
# fold of fixed vertices, --slip-boundary, a free boundary that moves.
set -u
vol=$1 qual=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; else echo "ok: $2"; fi; }

# gen OUT PLANE ORIENT TANGLE TYPE FIXED: a 6 x 6 grid on [0,1]^2 put in
# PLANE; TANGLE pushes two interior vertices through their neighbours;
# FIXED 'bnd' writes the boundary as a 'fixed' field of VTK type bit, 'all'
# every vertex
gen() {
  python3 - "$@" <<'PY'
import math, sys
out, plane, orient, tangle, typ, fixed = sys.argv[1:7]
n = 6
pts = [[i / n, j / n] for j in range(n + 1) for i in range(n + 1)]
idx = lambda i, j: j * (n + 1) + i
if tangle == 'yes':
    x, y = pts[idx(2, 2)]; pts[idx(2, 2)] = [x + 0.45, y + 0.4]
    x, y = pts[idx(4, 3)]; pts[idx(4, 3)] = [x - 0.4, y - 0.05]
def emb(k, p):
    x, y = p
    if plane == 'z0': return (x, y, 0.0)
    if plane == 'z5': return (x, y, 5.0)
    if plane == 'y': return (x, 0.25, y)
    if plane == 'tilted':
        return (1.5 + x * math.cos(0.5), 2.0 + y, -1.0 + x * math.sin(0.5))
    if plane == 'bump': return (x, y, 0.1 if k == idx(3, 3) else 0.0)
P = [emb(k, p) for k, p in enumerate(pts)]
cells = []
for j in range(n):
    for i in range(n):
        q = [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]
        cells += [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] if typ == 'tri' else [q]
if orient == 'cw': cells = [c[::-1] for c in cells]
if orient == 'mixed': cells[len(cells) // 2] = cells[len(cells) // 2][::-1]
bnd = set(k for k in range(len(pts)) if k % (n + 1) in (0, n) or k // (n + 1) in (0, n))
with open(out, 'w') as f:
    f.write('# vtk DataFile Version 3.0\nplanar\nASCII\nDATASET UNSTRUCTURED_GRID\n')
    f.write('POINTS %d double\n' % len(P))
    for p in P: f.write('%r %r %r\n' % p)
    f.write('CELLS %d %d\n' % (len(cells), sum(len(c) + 1 for c in cells)))
    for c in cells: f.write('%d %s\n' % (len(c), ' '.join(map(str, c))))
    f.write('CELL_TYPES %d\n' % len(cells))
    for c in cells: f.write('%d\n' % (5 if len(c) == 3 else 9))
    if fixed != 'none':
        f.write('POINT_DATA %d\nSCALARS fixed bit 1\nLOOKUP_TABLE default\n' % len(P))
        for k in range(len(P)): f.write('%d\n' % (1 if fixed == 'all' or k in bnd else 0))
PY
}

# compare IN OUT WHAT: WHAT is 'boundary' (the boundary vertices of the 6 x 6
# grid bit for bit as read), 'z=5' / 'y=0.25' (that coordinate of every
# vertex exactly), 'tilted' (every vertex within 1e-12 of the plane)
compare() {
  python3 - "$@" <<'PY'
import math, sys
def points(fn):
    L = open(fn).read().split('\n')
    i = next(k for k, l in enumerate(L) if l.startswith('POINTS'))
    n = int(L[i].split()[1]); vals = []
    k = i + 1
    while len(vals) < 3 * n:
        vals += [float(x) for x in L[k].split()]; k += 1
    return [vals[3 * j:3 * j + 3] for j in range(n)]
a, b = points(sys.argv[1]), points(sys.argv[2])
what, n = sys.argv[3], 6
if len(a) != len(b): sys.exit(1)
if what == 'boundary':
    bnd = [k for k in range(len(a)) if k % (n + 1) in (0, n) or k // (n + 1) in (0, n)]
    sys.exit(0 if all(a[k] == b[k] for k in bnd) else 1)
if what == 'z=5': sys.exit(0 if all(p[2] == 5.0 for p in b) else 1)
if what == 'y=0.25': sys.exit(0 if all(p[1] == 0.25 for p in b) else 1)
if what == 'tilted':
    nrm = (-math.sin(0.5), 0.0, math.cos(0.5)); o = (1.5, 2.0, -1.0)
    d = max(abs(sum((p[k] - o[k]) * nrm[k] for k in range(3))) for p in b)
    sys.exit(0 if d < 1e-12 else 1)
if what == 'moved':
    sys.exit(0 if any(a[k] != b[k] for k in range(len(a))) else 1)
sys.exit(2)
PY
}

# M (inverted corner simplices) as vm-quality counts it
inverted() { "$qual" -q "$1" | awk '$1 == "all" {print $4}'; }

# 1. tangled quads in z = 5, the boundary fixed by default
gen "$dir/z5.vtk" z5 ccw yes quad none
check '[ "$(inverted "$dir/z5.vtk")" -gt 0 ]' "z = 5: the input is tangled ($(inverted "$dir/z5.vtk") inverted)"
"$vol" --json "$dir/z5.vtk" "$dir/z5_out.vtk" >"$dir/z5.json" 2>"$dir/z5.err"
rc=$?
check '[ $rc -eq 0 ]' "z = 5: exit 0 (got $rc)"
check 'grep -q "a 2D mesh in the plane z = 5, optimized in that plane" "$dir/z5.err"' \
  "z = 5: says which plane"
check 'grep -q "\"valid\": true" "$dir/z5.json" && grep -q "\"verified\": true" "$dir/z5.json"' \
  "z = 5: JSON valid and verified"
check 'compare "$dir/z5.vtk" "$dir/z5_out.vtk" boundary' "z = 5: boundary vertices bit for bit"
check 'compare "$dir/z5.vtk" "$dir/z5_out.vtk" z=5' "z = 5: every z exactly 5"
check 'compare "$dir/z5.vtk" "$dir/z5_out.vtk" moved' "z = 5: the interior moved"
check '[ "$(inverted "$dir/z5_out.vtk")" = 0 ] && "$qual" -q --verify "$dir/z5_out.vtk" >/dev/null' \
  "z = 5: vm-quality finds none inverted, --verify certifies it"

# 2. a tilted plane, the boundary fixed by a field of VTK type bit
gen "$dir/tilt.vtk" tilted ccw yes quad bnd
"$vol" --free-boundary "$dir/tilt.vtk" "$dir/tilt_out.vtk" 2>"$dir/tilt.err"
rc=$?
check '[ $rc -eq 0 ]' "tilted: exit 0 with only the field's vertices fixed (got $rc)"
check 'grep -q "a 2D mesh in the plane through .* with normal" "$dir/tilt.err"' "tilted: says so"
check 'grep -q "24 fixed by field" "$dir/tilt.err"' "tilted: the bit field read (24 fixed)"
check 'compare "$dir/tilt.vtk" "$dir/tilt_out.vtk" boundary' "tilted: fixed vertices bit for bit"
check 'compare "$dir/tilt.vtk" "$dir/tilt_out.vtk" tilted' "tilted: every vertex in the plane"
check '[ "$(inverted "$dir/tilt_out.vtk")" = 0 ]' "tilted: vm-quality finds none inverted"

# 3. triangles ordered clockwise in z = 0: the boundary's orientation is
# the mesh's, in vm-volume and vm-quality alike
gen "$dir/cw.vtk" z0 cw yes tri none
"$vol" "$dir/cw.vtk" "$dir/cw_out.vtk" 2>"$dir/cw.err"
rc=$?
check '[ $rc -eq 0 ]' "clockwise triangles: exit 0 (got $rc)"
check 'grep -q "turn clockwise" "$dir/cw.err"' "clockwise: says which orientation it took"
"$qual" "$dir/cw_out.vtk" >"$dir/cwq.txt" 2>"$dir/cwq.err"
check 'grep -q "turn clockwise" "$dir/cwq.err" && [ "$(inverted "$dir/cw_out.vtk")" = 0 ]' \
  "clockwise: vm-quality takes the same orientation and finds none inverted"
check '[ "$(inverted "$dir/cw.vtk")" -gt 0 ] && [ "$(inverted "$dir/cw.vtk")" -lt 20 ]' \
  "clockwise: vm-quality counts the input's folds only ($(inverted "$dir/cw.vtk"))"

# 4. the plane y = 0.25
gen "$dir/y.vtk" y ccw yes tri none
"$vol" -q "$dir/y.vtk" "$dir/y_out.vtk"
rc=$?
check '[ $rc -eq 0 ] && compare "$dir/y.vtk" "$dir/y_out.vtk" y=0.25' \
  "y = 0.25: exit 0 (got $rc), every y exactly 0.25"

# 5. a vertex off the plane: refused, named, nothing written
gen "$dir/bump.vtk" bump ccw no quad none
"$vol" "$dir/bump.vtk" "$dir/bump_out.vtk" 2>"$dir/bump.err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/bump_out.vtk" ]' "off the plane: exit 1, no output (got $rc)"
check 'grep -q "not in one plane (vertex 24 at (0.5, 0.5, 0.1) is 0.1 off it).*vm-surface" "$dir/bump.err"' \
  "off the plane: names the vertex, how far, and vm-surface"
check '[ "$(wc -l <"$dir/bump.err")" -eq 1 ]' "off the plane: one line"

# 6. one element numbered the other way round
gen "$dir/mixed.vtk" z0 mixed no quad none
"$vol" "$dir/mixed.vtk" "$dir/mixed_out.vtk" 2>"$dir/mixed.err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/mixed_out.vtk" ]' "not oriented alike: exit 1, no output (got $rc)"
check 'grep -q "not oriented alike: elements [0-9]* and 18 run through their shared edge" "$dir/mixed.err"' \
  "not oriented alike: names element 18 and an edge"

# 7. every vertex fixed, folds left: at once, exit 3, --free-boundary named
gen "$dir/all.vtk" z0 ccw yes quad all
start=$(date +%s)
"$vol" "$dir/all.vtk" "$dir/all_out.vtk" 2>"$dir/all.err"
rc=$?
took=$(($(date +%s) - start))
check '[ $rc -eq 3 ] && [ $took -le 2 ]' "all fixed: exit 3 at once (got $rc after $took s)"
check 'grep -q "is inverted and all its vertices are fixed.*--free-boundary" "$dir/all.err" &&
  ! grep -q -- "--slip-boundary" "$dir/all.err"' "all fixed: names --free-boundary, not --slip-boundary"
check 'compare "$dir/all.vtk" "$dir/all_out.vtk" boundary && ! compare "$dir/all.vtk" "$dir/all_out.vtk" moved' \
  "all fixed: the input written unchanged"

# 7b. a degenerate element of fixed vertices (not inverted, never certifiable):
# a triangle whose three vertices lie on one line, all on the boundary, the
# boundary fixed: at once, exit 3, "degenerate", --free-boundary named
cat >"$dir/flat.vtk" <<'VTK'
# vtk DataFile Version 3.0
flat
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 double
0 0 0
1 0 0
2 0 0
1 1 0
CELLS 2 8
3 0 1 2
3 0 2 3
CELL_TYPES 2
5
5
VTK
start=$(date +%s)
"$vol" "$dir/flat.vtk" "$dir/flat_out.vtk" 2>"$dir/flat.err"
rc=$?
took=$(($(date +%s) - start))
check '[ $rc -eq 3 ] && [ $took -le 2 ]' "degenerate, all fixed: exit 3 at once (got $rc after $took s)"
check 'grep -q "element 0 (tri) is degenerate (det J = 0 in it: it cannot be certified) and all its vertices are fixed (1 such elements).*--free-boundary" "$dir/flat.err"' \
  "degenerate, all fixed: says so and names --free-boundary"

# 8. --slip-boundary takes volume meshes
"$vol" --slip-boundary "$dir/z5.vtk" "$dir/slip_out.vtk" 2>"$dir/slip.err"
rc=$?
check '[ $rc -eq 2 ] && grep -q -- "--slip-boundary takes volume meshes" "$dir/slip.err"' \
  "--slip-boundary on a planar mesh: exit 2 with the reason (got $rc)"

# 9. a free boundary: the square's corners round off, beyond the tolerance
gen "$dir/free.vtk" z0 ccw yes quad none
"$vol" --free-boundary "$dir/free.vtk" "$dir/free_out.vtk" 2>"$dir/free.err"
rc=$?
check '[ $rc -eq 3 ] && grep -q "the boundary moved by .* beyond --boundary-tolerance 0.01.*a larger --boundary-tolerance accepts it" "$dir/free.err"' \
  "free boundary: the move measured in the plane, exit 3 (got $rc)"
"$vol" -q --free-boundary --boundary-tolerance 0.2 "$dir/free.vtk" "$dir/free2_out.vtk"
rc=$?
check '[ $rc -eq 0 ]' "free boundary within a larger tolerance: exit 0 (got $rc)"

[ $fail -eq 0 ] && echo "volume-planar: all checks passed"
exit $fail
