#!/usr/bin/env bash
# bench/bench_half.sh: half models beside the whole, through the pipeline.
# Per model (plane.stl, cut at y = 0 by vm-convert --cut; the demo
# aircraft, vm-gen aircraft and --half) and thickness (T = 5 % and 20 % of
# the whole model's length, 20 layers): vm-surface, vm-prism, vm-fill,
# vm-convert to an OpenFOAM case, checkMesh (plain, and -allGeometry
# -allTopology: failed checks, cells below the determinant limit, weights
# below 0.05, max non-orthogonality) and potentialFoam (its last Phi
# residual); for the half, the columns in the plane, those of their
# vertices put back into it (0: every step kept them there) and the
# layer's other vertices on or beyond it (0), and the mirrored whole's
# checkMesh (topology: regions; failed checks).
# usage: bench/bench_half.sh BUILD_DIR [SHARED_DATA_DIR]   (prints a table)
set -u
build=$(cd "$1" && pwd)
data=${2:-$(cd "$(dirname "$0")/../.." && pwd)/shared/data}
bin=$build/apps
root=$(cd "$(dirname "$0")/.." && pwd)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
[ -z "${WM_PROJECT_DIR:-}" ] && [ -d /usr/share/openfoam ] && export WM_PROJECT_DIR=/usr/share/openfoam
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1 | tr -d '"'; }
now() { date +%s.%N; }
"$bin/vm-gen" aircraft "$dir/aircraft.stl" && "$bin/vm-gen" aircraft --half "$dir/aircraft-half.vmsh"
"$bin/vm-convert" -q --cut y=0 "$data/plane.stl" "$dir/plane-half.stl"
cp "$data/plane.stl" "$dir/plane.stl"
printf '| model | T/L | wall triangles | prisms + tets | surface / prism / fill s | full T | thickness/T min | in the plane: columns / put back / crossing | checkMesh plain / -all failed | det < 0.001 / weights < 0.05 | max non-orth. | potentialFoam last residual | mirrored whole: regions / failed |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for model in plane aircraft; do
  for t in 0.05 0.2; do
    for half in 0 1; do
      if [ $half = 1 ]; then
        name=$model-half
        in=$dir/$name.stl
        [ -f "$in" ] || in=$dir/$name.vmsh
      else
        name=$model in=$dir/$model.stl
      fi
      c=$dir/$name-$t
      s0=$(now)
      "$bin/vm-surface" -q "$in" "$c.surf.vmsh" 2>"$c.err" || { printf '| %s | %s | vm-surface failed: %s |\n' "$name" "$t" "$(tail -1 "$c.err")"; continue; }
      s1=$(now)
      "$bin/vm-prism" -q -t "$t" -n 20 --json "$c.surf.vmsh" "$c.prism.vmsh" >"$c.prism.json" 2>"$c.err" || { printf '| %s | %s | vm-prism failed: %s |\n' "$name" "$t" "$(tail -1 "$c.err")"; continue; }
      s2=$(now)
      "$bin/vm-fill" -q --json "$c.prism.vmsh" "$c.fill.vmsh" >"$c.fill.json" 2>"$c.err" || { printf '| %s | %s | vm-fill failed: %s |\n' "$name" "$t" "$(tail -1 "$c.err")"; continue; }
      s3=$(now)
      "$bin/vm-convert" -q "$c.fill.vmsh" "$c.foam" 2>/dev/null
      cp -r "$root/examples/foam/0" "$c.foam/" && cp "$root/examples/foam/system/"* "$c.foam/system/" &&
        cp "$root/examples/foam/constant/"*Properties "$c.foam/constant/"
      checkMesh -case "$c.foam" >"$c.cm0" 2>&1
      checkMesh -case "$c.foam" -allGeometry -allTopology >"$c.cm" 2>&1
      potentialFoam -case "$c.foam" >"$c.pf" 2>&1
      plain=$(grep -q "^Mesh OK" "$c.cm0" && echo OK || echo "$(sed -n 's/Failed \([0-9]*\) mesh checks./\1/p' "$c.cm0") failed")
      nall=$(grep -q "^Mesh OK" "$c.cm" && echo 0 || sed -n 's/Failed \([0-9]*\) mesh checks./\1/p' "$c.cm")
      ndet=$(sed -n 's/.*small determinant.*number of cells: \([0-9]*\).*/\1/p' "$c.cm")
      nw=$(sed -n 's/.*small interpolation weight.*number of faces: \([0-9]*\).*/\1/p' "$c.cm")
      no=$(sed -n 's/.*Mesh non-orthogonality Max: \([0-9.]*\).*/\1/p' "$c.cm")
      pf=$(grep "Solving for Phi" "$c.pf" | tail -1 | sed 's/.*Final residual = \([0-9.e+-]*\).*/\1/')
      sym="—" whole="—"
      if [ $half = 1 ]; then
        sym="$(json "$c.prism.json" symmetry_columns) / $(json "$c.prism.json" symmetry_snapped) / $(json "$c.prism.json" symmetry_crossing)"
        "$bin/vm-convert" -q --mirror "$c.fill.vmsh" "$c.whole.vmsh" && "$bin/vm-convert" -q "$c.whole.vmsh" "$c.whole.foam" 2>/dev/null
        checkMesh -case "$c.whole.foam" -allGeometry -allTopology >"$c.wcm" 2>&1
        whole="$(sed -n 's/.*Number of regions: \([0-9]*\).*/\1/p' "$c.wcm") / $(grep -q '^Mesh OK' "$c.wcm" && echo 0 || sed -n 's/Failed \([0-9]*\) mesh checks./\1/p' "$c.wcm")"
      fi
      printf '| %s | %s | %s | %s + %s | %.1f / %.1f / %.1f | %.1f %% | %.3f | %s | %s / %s | %s / %s | %s° | %s | %s |\n' \
        "$name" "$t" "$(json "$c.prism.json" wall_triangles)" "$(json "$c.prism.json" prisms)" "$(json "$c.fill.json" tets)" \
        "$(echo "$s1 - $s0" | bc)" "$(echo "$s2 - $s1" | bc)" "$(echo "$s3 - $s2" | bc)" \
        "$(echo "100 * $(json "$c.prism.json" full_fraction)" | bc -l)" "$(json "$c.prism.json" thickness_min)" \
        "$sym" "$plain" "${nall:-?}" "${ndet:-0}" "${nw:-0}" "${no:-?}" "${pf:-?}" "$whole"
      rm -rf "$c".*foam
    done
  done
done
