#!/usr/bin/env bash
# test/volume/test_half_plane.sh: a real aircraft surface as a half model,
# through every stage to a solver. ../shared/data/plane.stl cut at y = 0 by
# the test itself (vm-convert --cut y=0), then vm-surface, vm-prism
# (defaults: T = 5 %, 20 layers), vm-fill, an OpenFOAM case:
#  - the cut: 9,343 triangles, its border exactly in y = 0 (the surface
#    stage finds the plane);
#  - the layer: valid, its columns in the plane kept there (none put back),
#    no other vertex on or beyond it, the same share of columns at full
#    thickness as the whole model within 3 points (the whole: 94.9 %);
#  - the case: a patch 'symmetry' of type symmetryPlane in y = 0; plain
#    checkMesh "Mesh OK."; potentialFoam converges;
#  - the mirror check: the half and its image one region, every face of the
#    image's wall matched (the wall one closed surface).
# Skipped (77) without OpenFOAM or the data.
# usage: test_half_plane.sh VM_PRISM VM_FILL VM_CONVERT VM_SURFACE SOURCE_ROOT
set -u
prism=$1 fill=$2 conv=$3 surf=$4 root=$5
data=$root/../shared/data/plane.stl
[ -f "$data" ] || { echo "skip: $data not found"; exit 77; }
for p in checkMesh potentialFoam; do
  command -v $p >/dev/null 2>&1 || { echo "skip: $p (OpenFOAM) not on PATH"; exit 77; }
done
if [ -z "${WM_PROJECT_DIR:-}" ]; then
  for d in /usr/share/openfoam /usr/lib/openfoam/openfoam*; do
    [ -f "$d/etc/controlDict" ] && { export WM_PROJECT_DIR=$d; break; }
  done
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
jget() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1 | tr -d '"'; }

"$conv" --cut y=0 "$data" "$dir/h.stl" 2>"$dir/cut.log"
check '[ $? -eq 0 ] && grep -q "9343 triangles" "$dir/cut.log"' "vm-convert --cut y=0: $(tail -1 "$dir/cut.log" | cut -c1-120)"
"$surf" --json "$dir/h.stl" "$dir/h.surf.vmsh" >"$dir/s.json" 2>"$dir/s.log"
check '[ $? -eq 0 ] && grep -q "symmetry plane y=0" "$dir/s.log"' "vm-surface finds the plane y = 0"
"$prism" -q --json "$dir/h.surf.vmsh" "$dir/h.prism.vmsh" >"$dir/p.json"
check '[ $? -eq 0 ] && [ "$(jget "$dir/p.json" valid)" = true ]' "vm-prism: valid"
check '[ "$(jget "$dir/p.json" symmetry_plane)" = "y=0" ] && [ "$(jget "$dir/p.json" symmetry_snapped)" = 0 ] && [ "$(jget "$dir/p.json" symmetry_crossing)" = 0 ] && [ "$(jget "$dir/p.json" inverted_corner_tets)" = 0 ]' \
  "the $(jget "$dir/p.json" symmetry_columns) columns in y = 0 kept there, nothing across, no inverted tet"
full=$(jget "$dir/p.json" full_fraction)
check 'awk -v f="$full" "BEGIN { exit !(f > 0.919 && f <= 1) }"' "columns at full thickness ${full:-?} (the whole: 0.949)"
"$fill" -q --json "$dir/h.prism.vmsh" "$dir/h.fill.vmsh" >"$dir/f.json"
check '[ $? -eq 0 ] && [ "$(jget "$dir/f.json" symmetry_faces)" -gt 0 ]' "vm-fill: the plane in $(jget "$dir/f.json" symmetry_faces) triangles"
c=$dir/case.foam
"$conv" -q "$dir/h.fill.vmsh" "$c" 2>/dev/null
cp -r "$root/examples/foam/0" "$c/" && cp "$root/examples/foam/system/"* "$c/system/" &&
  cp "$root/examples/foam/constant/"*Properties "$c/constant/"
check 'grep -A2 "^ *symmetry$" "$c/constant/polyMesh/boundary" | grep -q "type *symmetryPlane;"' "the patch symmetry is a symmetryPlane"
checkMesh -case "$c" >"$dir/cm.log" 2>&1
check 'grep -q "^Mesh OK\.$" "$dir/cm.log"' "checkMesh: Mesh OK"
# (the patches' bounding boxes: with every check; its failures are #19's)
checkMesh -case "$c" -allGeometry -allTopology >"$dir/cma.log" 2>&1
grep -E "Failed|\*\*\*" "$dir/cma.log"
check 'grep -E "^ *symmetry " "$dir/cma.log" | grep -q "([-0-9.e+]* 0 [-0-9.e+]*) ([-0-9.e+]* 0 [-0-9.e+]*)"' \
  "the symmetry patch lies in y = 0: $(grep -E '^ *symmetry ' "$dir/cma.log" | tr -s ' ')"
grep -E "cells:|non-orthogonality Max|skewness|Mesh OK|Failed" "$dir/cm.log"
potentialFoam -case "$c" >"$dir/pf.log" 2>&1
rc=$?
last=$(grep "Solving for Phi" "$dir/pf.log" | tail -1 | sed 's/.*Final residual = \([0-9.e+-]*\).*/\1/')
check '[ $rc -eq 0 ] && awk -v x="$last" "BEGIN { exit !(x + 0 < 1e-6) }"' "potentialFoam converges (last Phi residual ${last:-?})"
"$conv" -q --mirror "$dir/h.fill.vmsh" "$dir/w.vmsh" && "$conv" -q "$dir/w.vmsh" "$dir/w.foam" 2>/dev/null
checkMesh -case "$dir/w.foam" -allTopology >"$dir/wcm.log" 2>&1
check 'grep -q "Number of regions: 1 (OK)" "$dir/wcm.log" && grep -E "^ *wall " "$dir/wcm.log" | grep -q "ok (closed singly connected)"' \
  "the mirrored whole: one region, the wall one closed surface"
exit $fail
