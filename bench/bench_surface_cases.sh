#!/bin/bash
# bench/bench_surface_cases.sh BUILD [BEFORE_BUILD]: vm-surface with its
# defaults on the project's hard generated shapes, plane.stl and the
# aircraft, one table row per case (and per build when BEFORE_BUILD, a
# build of an earlier commit, is given: the same runs side by side).
# Figures: triangles in and out; smallest angle in and out and triangles
# under 15 degrees (the stage's own sliver angle); two-sided Hausdorff
# distance to the input (% of its diagonal) and triangles whose normal
# opposes the input's (bench_surface --eval); CGAL's intersecting pairs
# (vm-surface --json); the input's corners and tips without a vertex of
# the result on them, and the farthest, relative to the local edge
# length; CPU seconds (user + system, 1 thread).
# SIZES="input graded curvature uniform" (environment; default: the
# defaults only) adds one row per --size for the newer build.
# Shapes: bench/surface_shapes.py (spindle: cone points and a row of
# needles; slivers: an icosphere with pulled vertices; inward: reversed),
# vm-gen wing (graded, sharp trailing edge), vm-gen aircraft (coarse and
# the demo), ../shared/data/plane.stl.
set -u
here=$(cd "$(dirname "$0")" && pwd)
build=$(cd "$1" && pwd)
before=${2:+$(cd "$2" && pwd)}
py=/usr/bin/python3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
gen=$build/apps/vm-gen
plane=${PLANE_STL:-$here/../../shared/data/plane.stl}
"$gen" sphere "$tmp/sphere.off" >/dev/null 2>&1
$py "$here/surface_shapes.py" spindle "$tmp/spindle.stl"
$py "$here/surface_shapes.py" slivers "$tmp/slivers.stl" "$tmp/sphere.off"
$py "$here/surface_shapes.py" inward "$tmp/inward.stl" "$tmp/sphere.off"
"$gen" wing "$tmp/wing.stl" >/dev/null 2>&1
"$gen" aircraft --resolution 1 "$tmp/coarse.stl" >/dev/null 2>&1
"$gen" aircraft "$tmp/demo.stl" >/dev/null 2>&1
cases="spindle slivers inward wing coarse demo"
[ -f "$plane" ] && { cp "$plane" "$tmp/plane.stl"; cases="$cases plane"; }

# smallest angle and triangles under 15 degrees of a surface file
angles() {
  "$build/apps/vm-convert" "$1" "$tmp/a.off" >/dev/null 2>&1
  $py - "$tmp/a.off" <<'PY'
import sys, math
t = open(sys.argv[1]).read().split()
nv, nf = int(t[1]), int(t[2]); i = 4
v = [tuple(map(float, t[i + 3 * k:i + 3 * k + 3])) for k in range(nv)]; i += 3 * nv
mn, under = 180.0, 0
for _ in range(nf):
    n = int(t[i]); f = [int(x) for x in t[i + 1:i + 1 + n]]; i += 1 + n
    m = 180.0
    for a in range(n):
        p, q, r = v[f[a]], v[f[(a + 1) % n]], v[f[(a - 1) % n]]
        u = [q[k] - p[k] for k in range(3)]; w = [r[k] - p[k] for k in range(3)]
        c = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
        m = min(m, math.degrees(math.atan2(math.sqrt(sum(x * x for x in c)), sum(u[k] * w[k] for k in range(3)))))
    mn = min(mn, m); under += m < 15
print("%d %.2f %d" % (nf, mn, under))
PY
}

echo "| case | build | triangles in / out | smallest angle in / out | under 15 deg in / out | Hausdorff % diag | opposing | intersecting pairs | corners+tips moved (farthest / local edge) | local deviation / edge: anywhere, features | CPU s | exit |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for c in $cases; do
  read -r nin ain uin <<<"$(angles "$tmp/$c.stl")"
  for b in ${before:+before} ${SIZES:-after}; do
    bin=$build/apps; [ "$b" = before ] && bin=$before/apps
    opts=; case $b in before|after) ;; *) opts="--size $b" ;; esac
    out=$tmp/$c.$b.vmsh
    /usr/bin/time -f "%U %S" -o "$tmp/time" "$bin/vm-surface" --json -q --threads 1 $opts \
      "$tmp/$c.stl" "$out" >"$tmp/json" 2>"$tmp/err"
    rc=$?
    cpu=$(awk '{printf "%.1f", $1 + $2}' "$tmp/time")
    if [ ! -s "$out" ]; then
      echo "| $c | $b | $nin / - | $ain / - | $uin / - | | | | | | $cpu | $rc: $(tail -n 1 "$tmp/err")|"
      continue
    fi
    read -r nout aout uout <<<"$(angles "$out")"
    ev=$("$build/bench/bench_surface" --eval "$out" "$tmp/$c.stl" 2>/dev/null)
    haus=$(sed -n 's/.*Hausdorff [^=]*= \([0-9.e+-]*\)%.*/\1/p' <<<"$ev")
    opp=$(sed -n 's/.*opposing the input.s normal \([0-9]*\).*/\1/p' <<<"$ev")
    corners=$(sed -n 's/.*tips of the input: \([0-9]*\) ([0-9]* cone points), \([0-9]*\) without.*farthest [0-9.e+-]* = \([0-9.]*\) of.*/\2 of \1 (\3)/p' <<<"$ev")
    pairs=$(sed -n 's/.*"self_intersections": \(-*[0-9]*\), "remesh_refused.*/\1/p' "$tmp/json")
    dev=$($py -c 'import json, sys
d = json.load(open(sys.argv[1])).get("deviation")
print("%.3g, %.3g" % (d["rel"], d["feature_rel"]) if d else "")' "$tmp/json" 2>/dev/null)
    echo "| $c | $b | $nin / $nout | $ain / $aout | $uin / $uout | $haus | $opp | $pairs | $corners | $dev | $cpu | $rc |"
  done
done
