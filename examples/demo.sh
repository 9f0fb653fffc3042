#!/usr/bin/env bash
# examples/demo.sh: set up a fresh Debian machine (packages, build) and run
# varmesh's main job on its bundled, generated example: the aircraft model
# through every stage of examples/Makefile (model -> surface -> prism layers
# -> tetrahedra out to the far field -> exports, an OpenFOAM case -> reports),
# checkMesh, simpleFoam (its wall pressure coefficient pictured) and
# potentialFoam on that case, then the volume stage on the
# paper's rotated cube.
# Results go to out/. Run as root (apt-get) or on a machine that has the
# packages of .ci/install-deps.
set -eu
# OpenMP threads sleep while they wait (see examples/Makefile)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
t0=$(date +%s)
bash .ci/install-deps
echo "== build (release-like, in build/; the first build takes a few minutes)"
[ -f build/build.ninja ] || meson setup build >/dev/null
ninja -C build >/dev/null
bin="$root/build/apps"
out="$root/out/pipeline"
mkdir -p "$out"
echo "== the pipeline on the generated aircraft: make -C examples (incremental)"
make -C examples --no-print-directory VM_BIN="$bin" OUT="$out"
foam="$out/aircraft.foam"
if [ -d "$foam/constant/polyMesh" ] && command -v checkMesh >/dev/null 2>&1; then
  # Debian's OpenFOAM finds its etc/ through WM_PROJECT_DIR, which it does not set
  [ -n "${WM_PROJECT_DIR:-}" ] || export WM_PROJECT_DIR=/usr/share/openfoam
  echo "== OpenFOAM on the solver-ready mesh: checkMesh, simpleFoam, potentialFoam ($foam)"
  checkMesh -case "$foam" >"$foam/checkMesh.log" 2>&1 || true
  grep -E "cells:|non-orthogonality Max|skewness|Mesh OK|Failed" "$foam/checkMesh.log" | sed 's/^ */  /'
  # laminar flow at Re ~ 1500 (examples/foam), 100 SIMPLE iterations from
  # the free stream (a few minutes); it reads 0/ and writes 100/, so it runs
  # before potentialFoam, which overwrites 0/
  steps=${SIMPLE_ITER:-100}
  foamDictionary -entry endTime -set "$steps" "$foam/system/controlDict" >/dev/null
  foamDictionary -entry writeInterval -set "$steps" "$foam/system/controlDict" >/dev/null
  if simpleFoam -case "$foam" >"$foam/simpleFoam.log" 2>&1 && [ -f "$foam/$steps/p" ]; then
    echo "  simpleFoam, $steps iterations: $(grep 'Solving for p' "$foam/simpleFoam.log" | head -1 | sed 's/^GAMG: *Solving for //; s/, Final.*//') ->" \
      "$(grep 'Solving for p' "$foam/simpleFoam.log" | tail -1 | sed 's/^GAMG: *Solving for //; s/, Final.*//')"
    # the wall coloured by the pressure coefficient
    if python3 examples/foam_wall_cp.py "$foam" "$steps" "$out/aircraft.wall-cp.vtk" >/dev/null &&
      "$bin/vm-quality" -q --report "$out/aircraft-report-cp" --report-field Cp \
        "$out/aircraft.wall-cp.vtk" >/dev/null; then
      echo "  wall Cp: $out/aircraft-report-cp/surface.png"
    fi
  else
    echo "  simpleFoam failed: $(grep -E -A2 'FATAL|Floating' "$foam/simpleFoam.log" | tail -2 | tr '\n' ' ')"
  fi
  if potentialFoam -case "$foam" >"$foam/potentialFoam.log" 2>&1; then
    echo "  potentialFoam: $(grep 'Solving for Phi' "$foam/potentialFoam.log" | tail -1 | sed 's/^GAMG: *//')"
  else
    echo "  potentialFoam failed: $(grep -A2 FATAL "$foam/potentialFoam.log" | tail -2 | tr '\n' ' ')"
  fi
fi
echo "== the volume stage on the paper's rotated cube (n = 16, inner cube turned by pi)"
"$bin/vm-gen" rotcube --n 16 --angle pi "$root/out/rotcube.vtk"
"$bin/vm-volume" --staged --progress-every 50 --report "$root/out/rotcube-report" \
  "$root/out/rotcube.vtk" "$root/out/rotcube-untangled.vtu"
echo
echo "== results ($(( $(date +%s) - t0 )) s in all)"
echo "in $out:"
for f in aircraft.stl aircraft.surface.vmsh aircraft.prism.vmsh aircraft.fill.vmsh aircraft.msh \
  aircraft.vtu aircraft.su2 aircraft.cgns aircraft.foam; do
  [ -e "$out/$f" ] && printf '  %-24s %s\n' "$f" "$(du -h "$out/$f" | cut -f1)"
done
for r in surface prism fill cp; do
  d="$out/aircraft-report-$r"
  if [ -s "$d/index.html" ]; then
    if [ "$r" = cp ]; then
      echo "  aircraft-report-cp/surface.png  the wall coloured by simpleFoam's pressure coefficient"
      continue
    fi
    echo "  aircraft-report-$r/index.html  (open in a browser: pictures and histograms)"
    sed -n '1,6p' "$d/quality.txt" | sed 's/^/      /'
  fi
done
echo "in $root/out:"
echo "  rotcube.vtk                 the tangled rotated cube (vm-quality says how tangled)"
echo "  rotcube-untangled.vtu       the untangled, optimized mesh (ParaView)"
echo "  rotcube-report/index.html   convergence plot, histograms, slices before and after"
