#!/usr/bin/env bash
# test/volume/test_fill_slivers.sh: the fill's tets of four envelope
# vertices on an envelope that wraps a wing's leading edge. A wing as Gmsh
# meshes one from CAD (test/support/wing_m6.geo: ONERA M6 planform, NACA
# 0010 sections; here 7,036 triangles sized by curvature), 3 layers at
# T = 5 %: around the leading edge the layer's top stretches the wall's
# small triangles chordwise about sevenfold, and Gmsh's Delaunay leaves
# flat tets of four envelope vertices there, which no vertex of the fill
# may move. The passes with a point in
# each sliver (halfway up its circumsphere, again while they leave fewer;
# the last one inserts its points in their slivers' cavities instead of
# meshing again) and then edge removal around the slivers left must bring
# them down: at most 20 of them (5 measured; 7 when the last pass meshed
# again with Gmsh, 82 with the layers of session 40, 131 with the passes
# alone, 200 with a single pass of a point a quarter of the longest edge
# up), some points inserted locally; no tet
# inverted (the merge checks that the envelope's triangles are still
# faces); the envelope's vertices bit-identical; the fill the same bit
# for bit on a second run.
set -u
prism=$1 fill=$2 conv=$3 geo=$4
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
if ! command -v gmsh >/dev/null 2>&1; then
  echo "FAIL: gmsh is not installed (.ci/install-deps installs it)"
  exit 1
fi
gmsh -2 "$geo" -clmax 0.08 -clmin 0.004 -clcurv 8 -o "$dir/wing.stl" -format stl >"$dir/gmsh.txt" 2>&1
check '[ -s "$dir/wing.stl" ]' "Gmsh meshes the wing"
"$prism" -q -t 0.05 -n 3 "$dir/wing.stl" "$dir/layer.vmsh"
check '[ $? -eq 0 ]' "vm-prism: 3 layers at 5 %"
"$fill" --json "$dir/layer.vmsh" "$dir/f1.vmsh" >"$dir/f1.json" 2>"$dir/f1.log"
check '[ $? -eq 0 ]' "vm-fill on the wing's layer"
ins=$(sed -n "s/.*fill: \([0-9]*\) of the [0-9]* points inserted in their slivers' cavities.*/\1/p" "$dir/f1.log")
check '[ -n "$ins" ] && [ "$ins" -gt 0 ]' "the last pass inserts its points locally (${ins:-no} points)"
flat=$(sed -n 's/.*"flat_envelope_tets": \([0-9]*\).*/\1/p' "$dir/f1.json")
check '[ -n "$flat" ] && [ "$flat" -le 20 ]' "flat tets of four envelope vertices: ${flat:-?} (at most 20)"
check '[ "$(grep -o "\"inverted\": 0" "$dir/f1.json" | wc -l)" -eq 2 ]' "no inverted tet before or after the optimization"
"$fill" -q "$dir/layer.vmsh" "$dir/f2.vmsh"
check 'cmp -s "$dir/f1.vmsh" "$dir/f2.vmsh"' "the same fill bit for bit on a second run"
"$conv" "$dir/layer.vmsh" "$dir/l.vmsht" 2>/dev/null && "$conv" "$dir/f1.vmsh" "$dir/f.vmsht" 2>/dev/null
n=$(sed -n 's/^vertices //p' "$dir/l.vmsht")
check '[ -n "$n" ] && diff <(sed -n "/^vertices/,+${n}p" "$dir/l.vmsht" | tail -n +2 | cut -d" " -f1-3) <(sed -n "/^vertices/,+${n}p" "$dir/f.vmsht" | tail -n +2 | cut -d" " -f1-3) >/dev/null' "the layer's $n vertices come first, bit-identical"
exit $fail
