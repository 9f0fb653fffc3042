#!/usr/bin/env bash
# test/volume/test_fill_half.sh: a half model through the pipeline, and a
# solver on what it writes. The upper half of a cube-sphere (vm-gen sphere
# --half: its border exactly in z = 0) and the whole one (its mirror image
# closing it, vm-convert --mirror):
#  - vm-prism (T = 10 % of the diameter, 10 layers) on both: the half's
#    layer is the whole's on its side (twice the prisms; full thickness
#    everywhere; thickness, scaled Jacobian, non-orthogonality and skewness within
#    1 %, 10 %, 3 degrees and 10 %), its columns in the plane kept there (none
#    put back, no other vertex on or below it);
#  - vm-fill (far field at 10 diameters): a half box, the plane meshed
#    between it and the layer;
#  - the OpenFOAM case (vm-convert): a patch 'symmetry' of type
#    symmetryPlane lying in z = 0; checkMesh -allGeometry -allTopology
#    "Mesh OK.", non-orthogonality below 70 degrees; potentialFoam
#    converges; simpleFoam (laminar, Re 200) runs 200 iterations with
#    falling residuals and a drag coefficient (on half the frontal area)
#    within 20 % of the standard drag curve's 0.806;
#  - the mirror check: the half and its image (vm-convert --mirror) are one
#    valid mesh: checkMesh -allGeometry -allTopology "Mesh OK.", twice the
#    cells, the wall one closed surface, no symmetry patch left.
# Skipped (77) when OpenFOAM is not installed.
# usage: test_fill_half.sh VM_GEN VM_PRISM VM_FILL VM_CONVERT SOURCE_ROOT
set -u
gen=$1 prism=$2 fill=$3 conv=$4 root=$5
for p in checkMesh potentialFoam simpleFoam; do
  if ! command -v $p >/dev/null 2>&1; then
    echo "skip: $p (OpenFOAM) not on PATH"
    exit 77
  fi
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
jget() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }

"$gen" sphere --half "$dir/h.vmsh" && "$conv" -q --mirror "$dir/h.vmsh" "$dir/w.vmsh"
check '[ $? -eq 0 ]' "vm-gen sphere --half, vm-convert --mirror"
"$prism" -q -t 0.1 -n 10 --json "$dir/h.vmsh" "$dir/h.prism.vmsh" >"$dir/hp.json" &&
  "$prism" -q -t 0.1 -n 10 --json "$dir/w.vmsh" "$dir/w.prism.vmsh" >"$dir/wp.json"
check '[ $? -eq 0 ]' "vm-prism on the half and on the whole"
hp=$(jget "$dir/hp.json" prisms) wp=$(jget "$dir/wp.json" prisms)
check '[ -n "$hp" ] && [ $((2 * hp)) -eq "$wp" ]' "prisms: half $hp, whole $wp"
check 'grep -q "\"symmetry_plane\": \"z=0\"" "$dir/hp.json" && [ "$(jget "$dir/hp.json" symmetry_snapped)" = 0 ] && [ "$(jget "$dir/hp.json" symmetry_crossing)" = 0 ]' \
  "the half's columns in z = 0 stay there ($(jget "$dir/hp.json" symmetry_columns) columns)"
for k in full_fraction thickness_min thickness_mean sj_min nonortho_max_deg skewness_max; do
  a=$(jget "$dir/hp.json" $k) b=$(jget "$dir/wp.json" $k)
  case $k in
  full_fraction) tol='a == 1 && b == 1' ;;
  thickness_*) tol='a > 0.99 * b && a < 1.01 * b' ;;
  sj_min) tol='a > 0.9 * b && a < 1.1 * b' ;;
  nonortho_max_deg) tol='a < b + 3 && a > b - 3' ;;
  skewness_max) tol='a < 1.1 * b && a > 0.9 * b' ;;
  esac
  check "[ -n \"$a\" ] && [ -n \"$b\" ] && awk -v a=\"$a\" -v b=\"$b\" 'BEGIN { a += 0; b += 0; exit !($tol) }'" "$k: half ${a:-?}, whole ${b:-?}"
done

"$fill" -q --farfield 10 --json "$dir/h.prism.vmsh" "$dir/h.fill.vmsh" >"$dir/hf.json"
check '[ $? -eq 0 ] && grep -q "\"symmetry_plane\": \"z=0\"" "$dir/hf.json" && [ "$(jget "$dir/hf.json" symmetry_faces)" -gt 0 ]' \
  "vm-fill: a half far field, the plane in $(jget "$dir/hf.json" symmetry_faces) triangles"
c=$dir/case.foam
"$conv" -q "$dir/h.fill.vmsh" "$c" 2>/dev/null
check '[ $? -eq 0 ] && grep -A2 "^ *symmetry$" "$c/constant/polyMesh/boundary" | grep -q "type *symmetryPlane;"' \
  "vm-convert: the patch symmetry is a symmetryPlane"
cp -r "$root/examples/foam/0" "$c/" && cp "$root/examples/foam/system/"* "$c/system/" &&
  cp "$root/examples/foam/constant/"*Properties "$c/constant/"
cat >>"$c/system/controlDict" <<'END'
functions
{
    forces
    {
        type forceCoeffs; libs ("libforces.so"); writeControl timeStep; writeInterval 1;
        patches (wall); rho rhoInf; rhoInf 1; CofR (0 0 0);
        liftDir (0 1 0); dragDir (1 0 0); pitchAxis (0 0 1);
        magUInf 1; lRef 2; Aref 1.5707963;
    }
}
END
checkMesh -case "$c" -allGeometry -allTopology >"$dir/cm.log" 2>&1
check 'grep -q "^Mesh OK\.$" "$dir/cm.log"' "checkMesh -allGeometry -allTopology: Mesh OK"
nonorth=$(sed -n 's/.*Mesh non-orthogonality Max: \([0-9.e+-]*\).*/\1/p' "$dir/cm.log")
check 'awk -v x="$nonorth" "BEGIN { exit !(x + 0 > 0 && x + 0 < 70) }"' "max non-orthogonality ${nonorth:-?} < 70"
check 'grep -E "^ *symmetry " "$dir/cm.log" | grep -q "(\([-0-9.e+]* [-0-9.e+]* 0\)) (\([-0-9.e+]* [-0-9.e+]* 0\))"' \
  "the symmetry patch lies in z = 0: $(grep -E '^ *symmetry ' "$dir/cm.log" | tr -s ' ')"
grep -E "cells:|non-orthogonality|skewness|determinant|interpolation weight|Mesh OK|Failed" "$dir/cm.log"
cells=$(sed -n 's/^ *cells: *\([0-9]*\).*/\1/p' "$dir/cm.log")

potentialFoam -case "$c" >"$dir/pf.log" 2>&1
rc=$?
last=$(grep "Solving for Phi" "$dir/pf.log" | tail -1 | sed 's/.*Final residual = \([0-9.e+-]*\).*/\1/')
check '[ $rc -eq 0 ] && ! grep -q FATAL "$dir/pf.log" && awk -v x="$last" "BEGIN { exit !(x + 0 < 1e-6) }"' "potentialFoam converges (exit $rc, last Phi residual ${last:-?})"
simpleFoam -case "$c" >"$dir/sf.log" 2>&1
rc=$?
check '[ $rc -eq 0 ] && grep -q "^Time = 200$" "$dir/sf.log"' "simpleFoam runs 200 iterations (exit $rc)"
res() { grep "Solving for $1," "$dir/sf.log" | sed 's/.*Initial residual = \([0-9.e+-]*\),.*/\1/' | sed -n "$2"; }
for f in Ux p; do
  a=$(res $f 1p) b=$(res $f '$p')
  check 'awk -v a="$a" -v b="$b" "BEGIN { exit !(a + 0 > 0 && b + 0 < (a + 0) / 100) }"' "simpleFoam: $f initial residual falls ${a:-?} -> ${b:-?}"
done
cd=$(tail -1 "$c/postProcessing/forces/0/coefficient.dat" 2>/dev/null | awk '{print $2}')
check 'awk -v x="$cd" "BEGIN { exit !(x + 0 > 0.806 * 0.8 && x + 0 < 0.806 * 1.2) }"' "half sphere at Re 200: Cd ${cd:-?} within 20 % of 0.806"

# the mirror check
"$conv" -q --mirror "$dir/h.fill.vmsh" "$dir/whole.fill.vmsh" &&
  "$conv" -q "$dir/whole.fill.vmsh" "$dir/whole.foam" 2>/dev/null
check '[ $? -eq 0 ]' "vm-convert --mirror: the whole"
checkMesh -case "$dir/whole.foam" -allGeometry -allTopology >"$dir/wcm.log" 2>&1
wcells=$(sed -n 's/^ *cells: *\([0-9]*\).*/\1/p' "$dir/wcm.log")
check 'grep -q "^Mesh OK\.$" "$dir/wcm.log" && [ -n "$cells" ] && [ "$wcells" = $((2 * cells)) ]' \
  "the whole (half and image): Mesh OK, cells $wcells = 2 x $cells"
check 'grep -E "^ *wall " "$dir/wcm.log" | grep -q "ok (closed singly connected)" && ! grep -qE "^ *symmetry " "$dir/wcm.log"' \
  "the whole's wall is one closed surface, no symmetry patch"
exit $fail
