#!/usr/bin/env bash
# bench/bench_fill.sh: the fill stage on real and generated models, with
# its peer in the same run. Per case (plane.stl and the demo aircraft, 20
# layers, T = 5 % and 20 % of the model's length): vm-prism, then vm-fill
# (tets, its time and peak memory, min dihedral angle and min scaled
# Jacobian of the tets, the largest volume ratio across the envelope and
# between tets, flat tets of four envelope vertices, and the fill's own
# OpenFOAM figures before and after its finite-volume relief: faces beyond
# 70 degrees, determinants below 0.001, weights below 0.05), then OpenFOAM's
# checkMesh on the case vm-convert writes (max non-orthogonality and
# skewness, failed checks plain and with -allGeometry -allTopology), and
# the peer: Gmsh's own fill of the same envelope from files
# (bench/peer_gmsh_fill.py: HXT, default sizing).
# usage: bench/bench_fill.sh BUILD_DIR [SHARED_DATA_DIR]   (prints a table)
set -u
build=$(cd "$1" && pwd)
data=${2:-$(cd "$(dirname "$0")/../.." && pwd)/shared/data}
bin=$build/apps
here=$(cd "$(dirname "$0")" && pwd)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
[ -z "${WM_PROJECT_DIR:-}" ] && [ -d /usr/share/openfoam ] && export WM_PROJECT_DIR=/usr/share/openfoam
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$bin/vm-gen" aircraft "$dir/aircraft.stl"
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }
printf '| case | T/L | prisms | prism s | tets | fill s | fill MB | min dihedral (before opt) | min SJ | vol ratio env / tets | flat env tets | fill tets: faces > 70° / det < 0.001 / weights < 0.05, before → after the relief | checkMesh non-orth / skew | failed plain / all | Gmsh peer: tets, s, exact env vertices |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
# the three counts of the fill's OpenFOAM figures (fv_before or fv_after)
fv() { grep -o "\"fv_$2\": {[^}]*}" "$1" | sed 's/.*"nonortho_over70": \([0-9]*\).*"weight_under005": \([0-9]*\).*"det_under0001": \([0-9]*\).*/\1 \/ \3 \/ \2/'; }
for model in "$data/plane.stl" "$dir/aircraft.stl"; do
  name=$(basename "$model" .stl)
  for t in 0.05 0.2; do
    c=$dir/$name-$t
    s0=$(date +%s.%N)
    "$bin/vm-prism" -q -t "$t" -n 20 "$model" "$c.prism.vmsh" 2>"$c.prism.err"
    prc=$?
    s1=$(date +%s.%N)
    if [ ! -s "$c.prism.vmsh" ]; then
      printf '| %s | %s | vm-prism failed (exit %s): %s |\n' "$name" "$t" "$prc" "$(tail -1 "$c.prism.err")"
      continue
    fi
    /usr/bin/time -f '%M' -o "$c.rss" "$bin/vm-fill" -q --json "$c.prism.vmsh" "$c.fill.vmsh" >"$c.json" 2>"$c.fill.err"
    frc=$?
    if [ $frc -ne 0 ]; then
      printf '| %s | %s | vm-fill failed (exit %s): %s |\n' "$name" "$t" "$frc" "$(tail -1 "$c.fill.err")"
      continue
    fi
    nonorth=- skew=- fplain=- fall=-
    if command -v checkMesh >/dev/null 2>&1; then
      "$bin/vm-convert" -q "$c.fill.vmsh" "$c.foam" 2>/dev/null
      checkMesh -case "$c.foam" >"$c.cm" 2>&1
      checkMesh -case "$c.foam" -allGeometry -allTopology >"$c.cma" 2>&1
      nonorth=$(sed -n 's/.*non-orthogonality Max: \([0-9.]*\).*/\1/p' "$c.cm" | head -1)
      skew=$(sed -n 's/.*Max skewness = \([0-9.]*\).*/\1/p' "$c.cm" | head -1)
      fplain=$(sed -n 's/^Failed \([0-9]*\) mesh checks.*/\1/p' "$c.cm"); grep -q "^Mesh OK" "$c.cm" && fplain=0
      fall=$(sed -n 's/^Failed \([0-9]*\) mesh checks.*/\1/p' "$c.cma"); grep -q "^Mesh OK" "$c.cma" && fall=0
    fi
    peer=-
    if /usr/bin/python3 -c 'import gmsh, meshio' 2>/dev/null; then
      "$bin/vm-convert" -q "$c.prism.vmsh" "$c.prism.msh" 2>/dev/null
      p=$(/usr/bin/python3 "$here/peer_gmsh_fill.py" "$c.prism.msh" 2>/dev/null | tail -1)
      peer="$(echo "$p" | sed -n 's/.*"tets": \([0-9]*\).*"seconds": \([0-9.]*\).*"exact": \([0-9]*\).*"envelope_vertices": \([0-9]*\).*/\1, \2, \3 of \4/p')"
    fi
    printf '| %s | %s | %s | %.1f | %s | %.1f | %d | %.2f (%.2f) | %.3f | %.3g / %.3g | %s | %s → %s | %s / %s | %s / %s | %s |\n' \
      "$name" "$t" "$(json "$c.json" layer_cells)" "$(echo "$s1 - $s0" | bc)" "$(json "$c.json" tets)" \
      "$(json "$c.json" time_total)" "$(( $(cat "$c.rss") / 1024 ))" \
      "$(sed -n 's/.*"after": {"min_dihedral": \([^,]*\).*/\1/p' "$c.json")" \
      "$(sed -n 's/.*"before": {"min_dihedral": \([^,]*\).*/\1/p' "$c.json")" \
      "$(sed -n 's/.*"after": {.*"sj_min": \([^,]*\).*/\1/p' "$c.json")" \
      "$(sed -n 's/.*"after": {.*"vol_ratio_envelope": \([^,]*\).*/\1/p' "$c.json")" \
      "$(sed -n 's/.*"after": {.*"vol_ratio_tets": \([^,]*\).*/\1/p' "$c.json")" \
      "$(json "$c.json" flat_envelope_tets)" "$(fv "$c.json" before)" "$(fv "$c.json" after)" \
      "$nonorth" "$skew" "$fplain" "$fall" "$peer"
  done
done
