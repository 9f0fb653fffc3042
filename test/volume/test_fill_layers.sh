#!/usr/bin/env bash
# test/volume/test_fill_layers.sh: a solver runs on a layer whose layers end
# per region (vm-prism --region-layers, issue 24 item 5): vm-gen's coarse
# aircraft, the fuselage at 10 of 20 layers (prisms, and pyramids and tets
# where the counts meet), vm-fill out to the far field, an OpenFOAM case.
#  - vm-fill judges only its own tets: the layer's transition tets are not
#    "flat tets of four envelope vertices" (before the fix it counted 536 of
#    them and broke them with points; the uniform layer has 2), and its
#    figures are its tets';
#  - the hybrid mesh is certified valid (vm-quality --verify);
#  - checkMesh says "Mesh OK." and potentialFoam converges (final Phi
#    residual below 1e-6), when OpenFOAM is installed.
# usage: test_fill_layers.sh VM_GEN VM_PRISM VM_FILL VM_CONVERT VM_QUALITY SOURCE_ROOT
set -u
gen=$1 prism=$2 fill=$3 conv=$4 quality=$5 root=$6
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }

"$gen" aircraft --resolution 1 --components "$dir/a.vmsh" &&
  "$prism" -q --json --region-layers component:0=10 "$dir/a.vmsh" "$dir/l.vmsh" >"$dir/l.json"
check "[ \$? -eq 0 ] && [ \$(json $dir/l.json tets) -gt 0 ] && [ \$(json $dir/l.json pyramids) -gt 0 ]" \
  "the layer: $(json "$dir/l.json" prisms) prisms, $(json "$dir/l.json" pyramids) pyramids, $(json "$dir/l.json" tets) tets"
"$fill" -q --json "$dir/l.vmsh" "$dir/h.vmsh" >"$dir/f.json" 2>"$dir/f.err"
rc=$?
flat=$(json "$dir/f.json" flat_envelope_tets)
check "[ $rc -eq 0 ] && [ ${flat:-999} -le 10 ]" "vm-fill: exit $rc, ${flat:-?} flat envelope tets (the layer's own tets not among them)"
"$quality" --verify "$dir/h.vmsh" >"$dir/q.log" 2>&1
check "[ \$? -eq 0 ] && grep -q '0 invalid, 0 undecided' $dir/q.log" "vm-quality --verify: $(grep -o 'certified.*undecided' "$dir/q.log")"

for p in checkMesh potentialFoam; do
  if ! command -v $p >/dev/null 2>&1; then
    echo "skip: $p (OpenFOAM) not on PATH"
    exit $fail
  fi
done
if [ -z "${WM_PROJECT_DIR:-}" ]; then
  for d in /usr/share/openfoam /usr/lib/openfoam/openfoam*; do
    [ -f "$d/etc/controlDict" ] && { export WM_PROJECT_DIR=$d; break; }
  done
fi
c=$dir/case.foam
"$conv" -q "$dir/h.vmsh" "$c" 2>/dev/null
cp -r "$root/examples/foam/0" "$c/" && cp "$root/examples/foam/system/"* "$c/system/" &&
  cp "$root/examples/foam/constant/"*Properties "$c/constant/"
checkMesh -case "$c" >"$dir/cm.log" 2>&1
check 'grep -q "^Mesh OK\.$" "$dir/cm.log"' "checkMesh: $(grep -E 'pyramids:|Mesh OK|Failed' "$dir/cm.log" | tr -s ' ' | tr '\n' ' ')"
potentialFoam -case "$c" >"$dir/pf.log" 2>&1
rc=$?
last=$(grep "Solving for Phi" "$dir/pf.log" | tail -1 | sed 's/.*Final residual = \([0-9.e+-]*\).*/\1/')
check '[ $rc -eq 0 ] && ! grep -q FATAL "$dir/pf.log" && awk -v x="$last" "BEGIN { exit !(x + 0 < 1e-6) }"' "potentialFoam converges (exit $rc, last Phi residual ${last:-?})"
exit $fail
