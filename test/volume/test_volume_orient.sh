#!/usr/bin/env bash
# test/volume/test_volume_orient.sh: vm-volume on a volume mesh whose cells
# are numbered the other way round from VTK's convention (a mirror's: its
# total signed volume is negative) untangles it in that orientation instead
# of calling every cell inverted, and writes every coordinate back; and
# --reference: target shapes from the same mesh in its rest shape, checked
# to be that mesh and numbered the same way round.
set -u
gen=$1 vol=$2 qual=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $2"; fail=1; else echo "ok: $2"; fi; }

# mirror IN OUT: x negated (exact), the connectivity as it is
mirror() {
  awk 'BEGIN { n = -1 }
       /^POINTS/ { n = $2; print; next }
       n > 0 { for (i = 1; i <= NF; i += 3) { $i = ($i ~ /^-/) ? substr($i, 2) : "-" $i }
               n -= NF / 3; print; next }
       { print }' "$1" >"$2"
}
# inverted corner simplices as vm-quality counts them (VTK's convention)
inverted() { "$qual" -q "$1" | awk '$1 == "all" {print $4}'; }

"$gen" rotcube --n 8 --angle pi/2 --tets "$dir/t.vtk" || exit 1
"$gen" rotcube --n 8 --angle 0 --tets "$dir/rest.vtk" || exit 1
mirror "$dir/t.vtk" "$dir/tm.vtk"
mirror "$dir/rest.vtk" "$dir/restm.vtk"
ncell=$(awk '/^CELLS/ {print $2}' "$dir/t.vtk")
check '[ "$(inverted "$dir/tm.vtk")" -gt $((ncell / 2)) ]' \
  "the mirrored cube: most cells inverted by VTK's convention ($(inverted "$dir/tm.vtk") of $ncell)"

"$vol" --json "$dir/tm.vtk" "$dir/tm_out.vtk" >"$dir/tm.json" 2>"$dir/tm.err"
rc=$?
check '[ $rc -eq 0 ]' "numbered the other way round: exit 0 (got $rc)"
check 'grep -q "numbered the other way round from VTK.s convention" "$dir/tm.err" &&
  grep -q "warning: .*vm-quality and solvers read its cells as inverted" "$dir/tm.err"' \
  "says which orientation it took, and what solvers will read"
check 'grep -q "\"orientation_reversed\": true" "$dir/tm.json" && grep -q "\"valid\": true" "$dir/tm.json"' \
  "JSON: orientation_reversed, valid"
# mirrored back, the result is the untangled cube in VTK's convention
mirror "$dir/tm_out.vtk" "$dir/back.vtk"
check '[ "$(inverted "$dir/back.vtk")" = 0 ] && "$qual" -q --verify "$dir/back.vtk" >/dev/null' \
  "mirrored back: none inverted, certified"
# the outer cube's vertices (a coordinate +-0.5) written back bit for bit
same_boundary() {
  python3 - "$1" "$2" <<'PY'
import sys
def pts(fn):
    L = open(fn).read().split('\n')
    i = next(k for k, l in enumerate(L) if l.startswith('POINTS'))
    n, v, k = int(L[i].split()[1]), [], i + 1
    while len(v) < 3 * n:
        v += [float(x) for x in L[k].split()]; k += 1
    return [tuple(v[3 * j:3 * j + 3]) for j in range(n)]
a, b = pts(sys.argv[1]), pts(sys.argv[2])
bnd = [j for j in range(len(a)) if any(abs(c) == 0.5 for c in a[j])]
sys.exit(0 if len(a) == len(b) and len(bnd) > 0 and all(a[j] == b[j] for j in bnd) else 1)
PY
}
check 'same_boundary "$dir/tm.vtk" "$dir/tm_out.vtk"' "the boundary written back bit for bit"

# --reference: the same cube unturned as the rest shape
"$vol" --json --reference "$dir/restm.vtk" "$dir/tm.vtk" "$dir/ref_out.vtk" >"$dir/ref.json" 2>"$dir/ref.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/ref.json"' \
  "--reference: exit 0, valid (got $rc: $(tail -1 "$dir/ref.err"))"
"$vol" --reference "$dir/rest.vtk" "$dir/tm.vtk" "$dir/bad_out.vtk" 2>"$dir/bad.err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/bad_out.vtk" ] && grep -q "not numbered the same way round" "$dir/bad.err"' \
  "--reference numbered the other way: exit 1, said, nothing written (got $rc)"
"$gen" rotcube --n 7 --angle 0 --tets "$dir/small.vtk" || exit 1
"$vol" --reference "$dir/small.vtk" "$dir/t.vtk" "$dir/bad_out.vtk" 2>"$dir/bad.err"
rc=$?
check '[ $rc -eq 1 ] && grep -q "not .*t.vtk.s mesh in another shape: .* vertices and .* elements against" "$dir/bad.err"' \
  "--reference of another mesh: exit 1, said (got $rc)"
"$vol" --reference "$dir/rest.vtk" --target-size 0.1 "$dir/t.vtk" "$dir/bad_out.vtk" 2>/dev/null
rc=$?
check '[ $rc -eq 2 ]' "--reference with --target-size: a usage error (got $rc)"

[ $fail -eq 0 ] && echo "volume-orient: all checks passed"
exit $fail
