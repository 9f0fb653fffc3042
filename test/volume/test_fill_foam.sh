#!/usr/bin/env bash
# test/volume/test_fill_foam.sh: a solver runs on what the pipeline writes.
# A sphere (vm-gen sphere, 1,280 triangles) gets a 10-layer prism layer
# (vm-prism, T = 10 % of its diameter), the tets out to a far-field box at
# 10 diameters (vm-fill), and an OpenFOAM case (vm-convert, the case files
# of examples/foam). Then:
#  - checkMesh with every check (-allGeometry -allTopology): "Mesh OK.",
#    max non-orthogonality below 70 degrees;
#  - potentialFoam runs (exit 0, no FATAL) and its last solve for Phi
#    converges (final residual below 1e-6);
#  - simpleFoam, laminar at Re = U D / nu = 200, runs 200 iterations without
#    a floating-point exception, the initial residuals of Ux and p fall by
#    at least 100 times, and the drag coefficient is within 20 % of the
#    standard drag curve's 0.806 (Schiller-Naumann: 24/Re (1 + 0.15 Re^0.687);
#    the steady axisymmetric wake holds up to Re of about 210); the wall's
#    pressure coefficient (examples/foam_wall_cp.py) peaks at about 1.
# Skipped (77) when OpenFOAM is not installed.
# usage: test_fill_foam.sh VM_GEN VM_PRISM VM_FILL VM_CONVERT SOURCE_ROOT
set -u
gen=$1 prism=$2 fill=$3 conv=$4 root=$5
for p in checkMesh potentialFoam simpleFoam; do
  if ! command -v $p >/dev/null 2>&1; then
    echo "skip: $p (OpenFOAM) not on PATH"
    exit 77
  fi
done
# Debian's OpenFOAM finds its etc/ through WM_PROJECT_DIR, which it does not set
if [ -z "${WM_PROJECT_DIR:-}" ]; then
  for d in /usr/share/openfoam /usr/lib/openfoam/openfoam*; do
    [ -f "$d/etc/controlDict" ] && { export WM_PROJECT_DIR=$d; break; }
  done
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

"$gen" sphere --level 3 "$dir/s.stl" &&
  "$prism" -q -t 0.1 -n 10 "$dir/s.stl" "$dir/s.prism.vmsh" &&
  "$fill" -q --farfield 10 --json "$dir/s.prism.vmsh" "$dir/s.fill.vmsh" >"$dir/fill.json"
check '[ $? -eq 0 ]' "vm-gen sphere, vm-prism, vm-fill"
c=$dir/case.foam
"$conv" -q "$dir/s.fill.vmsh" "$c" 2>/dev/null
check '[ $? -eq 0 ] && [ -s "$c/constant/polyMesh/owner" ]' "vm-convert s.fill.vmsh case.foam"
cp -r "$root/examples/foam/0" "$c/" && cp "$root/examples/foam/system/"* "$c/system/" &&
  cp "$root/examples/foam/constant/"*Properties "$c/constant/"
cat >>"$c/system/controlDict" <<'END'
functions
{
    forces
    {
        type forceCoeffs; libs ("libforces.so"); writeControl timeStep; writeInterval 1;
        patches (wall); rho rhoInf; rhoInf 1; CofR (0 0 0);
        liftDir (0 0 1); dragDir (1 0 0); pitchAxis (0 1 0);
        magUInf 1; lRef 2; Aref 3.14159265;
    }
}
END

checkMesh -case "$c" -allGeometry -allTopology >"$dir/cm.log" 2>&1
check 'grep -q "^Mesh OK\.$" "$dir/cm.log"' "checkMesh -allGeometry -allTopology: Mesh OK"
nonorth=$(sed -n 's/.*Mesh non-orthogonality Max: \([0-9.e+-]*\).*/\1/p' "$dir/cm.log")
check 'awk -v x="$nonorth" "BEGIN { exit !(x + 0 > 0 && x + 0 < 70) }"' "max non-orthogonality ${nonorth:-?} < 70"
grep -E "cells:|non-orthogonality|skewness|determinant|interpolation weight|Mesh OK|Failed" "$dir/cm.log"

potentialFoam -case "$c" >"$dir/pf.log" 2>&1
rc=$?
last=$(grep "Solving for Phi" "$dir/pf.log" | tail -1 | sed 's/.*Final residual = \([0-9.e+-]*\).*/\1/')
check '[ $rc -eq 0 ] && ! grep -q FATAL "$dir/pf.log" && awk -v x="$last" "BEGIN { exit !(x + 0 < 1e-6) }"' "potentialFoam converges (exit $rc, last Phi residual ${last:-?})"

simpleFoam -case "$c" >"$dir/sf.log" 2>&1
rc=$?
check '[ $rc -eq 0 ] && grep -q "^Time = 200$" "$dir/sf.log"' "simpleFoam runs 200 iterations, no floating-point exception (exit $rc)"
res() { grep "Solving for $1," "$dir/sf.log" | sed 's/.*Initial residual = \([0-9.e+-]*\),.*/\1/' | sed -n "$2"; }
for f in Ux p; do
  a=$(res $f 1p) b=$(res $f '$p')
  check 'awk -v a="$a" -v b="$b" "BEGIN { exit !(a + 0 > 0 && b + 0 < (a + 0) / 100) }"' "simpleFoam: $f initial residual falls ${a:-?} -> ${b:-?}"
done
cd=$(tail -1 "$c/postProcessing/forces/0/coefficient.dat" 2>/dev/null | awk '{print $2}')
check 'awk -v x="$cd" "BEGIN { exit !(x + 0 > 0.806 * 0.8 && x + 0 < 0.806 * 1.2) }"' "sphere at Re 200: Cd ${cd:-?} within 20 % of 0.806"
# the wall's pressure coefficient as the demo pictures it
# (examples/foam_wall_cp.py): stagnation at the front (Cp about 1, a little
# more at this Re), suction at the sides
cpl=$(python3 "$root/examples/foam_wall_cp.py" "$c" 200 "$dir/cp.vtk" 2>&1)
cmin=$(echo "$cpl" | sed -n 's/.*Cp from \([-0-9.]*\) to \([-0-9.]*\).*/\1/p')
cmax=$(echo "$cpl" | sed -n 's/.*Cp from \([-0-9.]*\) to \([-0-9.]*\).*/\2/p')
check '[ -s "$dir/cp.vtk" ] && grep -q "^SCALARS Cp double 1" "$dir/cp.vtk" && awk -v a="$cmin" -v b="$cmax" "BEGIN { exit !(b + 0 > 0.95 && b + 0 < 1.4 && a + 0 < -0.2) }"' "wall Cp from ${cmin:-?} to ${cmax:-?}: stagnation about 1, suction below -0.2 ($cpl)"
exit $fail
