#!/usr/bin/env bash
# test/cli/test_convert_cli.sh: vm-convert and vm-quality end to end:
# plane.stl -> .vmsh -> .vtu -> .vmsh keeps geometry and connectivity bit
# for bit; every output format round-trips; bad input gives a one-line
# error, exit 1 and no output; usage errors exit 2; --strict exits 3 on loss.
set -u
conv=$1 qual=$2 gen=$3
plane="$VM_SOURCE_ROOT/../shared/data/plane.stl"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }

if [ -f "$plane" ]; then
  "$conv" -q "$plane" "$dir/p1.vmsh" && "$conv" -q "$dir/p1.vmsh" "$dir/p.vtu" &&
    "$conv" -q "$dir/p.vtu" "$dir/p2.vmsh"
  check '[ $? -eq 0 ]' "plane.stl -> vmsh -> vtu -> vmsh converts"
  check 'cmp -s "$dir/p1.vmsh" "$dir/p2.vmsh"' "the two .vmsh files are byte-identical"
  "$qual" --json "$dir/p2.vmsh" >"$dir/q.json"
  check 'grep -q "\"tri\": {\"elements\": 17456" "$dir/q.json"' "17,456 triangles kept"
  check 'grep -q "\"vertices\": 8730" "$dir/q.json"' "8,730 vertices (duplicates merged)"
  # the surface as SU2 and CGNS, and back to .vtu: the same coordinates bit
  # for bit and the same triangles in the same order
  "$conv" -q "$dir/p1.vmsh" "$dir/ref_p.vmsht"
  sect() { sed -n "/^vertices/,/^fields/{/^fields/!p}" "$1"; }
  "$conv" "$plane" "$dir/x.su2" 2>"$dir/err_su2"
  check '[ $? -eq 0 ]' "plane.stl -> .su2 converts"
  check '[ $(grep -c "SU2.s solvers need volume cells" "$dir/err_su2") -eq 1 ]' "one warning that the .su2 holds a surface mesh"
  check 'grep -q "^NMARK= 0" "$dir/x.su2" && grep -q "^NELEM= 17456" "$dir/x.su2"' ".su2 holds 17,456 triangles, no markers"
  formats=su2
  if "$conv" -q "$plane" "$dir/x.cgns" 2>"$dir/err_cgns"; then
    formats="su2 cgns"
  else
    check 'grep -q "no CGNS support" "$dir/err_cgns"' "plane.stl -> .cgns fails only without libcgns"
  fi
  for f in $formats; do
    "$conv" -q "$dir/x.$f" "$dir/y_$f.vtu" && "$conv" -q "$dir/y_$f.vtu" "$dir/y_$f.vmsht"
    check '[ $? -eq 0 ]' "plane.stl -> .$f -> .vtu converts"
    check 'diff <(sect "$dir/ref_p.vmsht") <(sect "$dir/y_$f.vmsht") >/dev/null' ".$f -> .vtu keeps coordinates bit for bit and the triangles in order"
    "$qual" --json "$dir/y_$f.vtu" >"$dir/q_$f.json"
    check 'grep -q "\"tri\": {\"elements\": 17456" "$dir/q_$f.json"' ".$f -> .vtu: 17,456 triangles"
  done
else
  echo "skip: $plane not found"
fi

"$gen" rotcube --n 4 --angle pi/2 --mixed "$dir/m.vmsh"
for f in vtk vtu msh mesh vmsht; do
  "$conv" -q "$dir/m.vmsh" "$dir/m.$f" && "$conv" -q "$dir/m.$f" "$dir/back_$f.vmsht"
  check '[ $? -eq 0 ]' "mixed mesh through .$f"
  "$conv" -q "$dir/m.vmsh" "$dir/ref.vmsht"
  # coordinates and flags must match exactly, elements as a set (MEDIT
  # groups elements by type)
  check 'diff <(sed -n "/^vertices/,/^elements/p" "$dir/ref.vmsht") <(sed -n "/^vertices/,/^elements/p" "$dir/back_$f.vmsht") >/dev/null' ".$f keeps coordinates and flags bit for bit"
  check 'diff <(sed -n "/^elements/,/^fields/{/^fields/!p}" "$dir/ref.vmsht" | sort) <(sed -n "/^elements/,/^fields/{/^fields/!p}" "$dir/back_$f.vmsht" | sort) >/dev/null' ".$f keeps the elements"
done
"$conv" --binary -q "$dir/m.vmsh" "$dir/mb.vtk" && "$conv" --binary -q "$dir/m.vmsh" "$dir/mb.msh"
check '[ $? -eq 0 ]' "binary VTK and msh"

printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\n' >"$dir/bad.stl"
"$conv" "$dir/bad.stl" "$dir/bad.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ]' "truncated STL exits 1 (got $rc)"
check '[ $(wc -l <"$dir/err") -eq 1 ] && grep -q "bad.stl" "$dir/err"' "one-line error naming the file: $(cat "$dir/err")"
check '[ ! -e "$dir/bad.vmsh" ]' "no output on failure"
"$conv" "$dir/m.vmsh" 2>/dev/null
check '[ $? -eq 2 ]' "missing OUT is a usage error"
"$conv" --strict -q "$dir/m.vmsh" "$dir/m_strict.stl" 2>/dev/null
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/m_strict.stl" ]' "--strict refuses a volume mesh to STL and writes nothing ($rc)"
"$conv" --strict "$dir/m.vmsh" "$dir/m_strict.mesh" 2>/dev/null
rc=$?
check '[ $rc -eq 3 ] && [ ! -e "$dir/m_strict.mesh" ]' "--strict refuses a lossy conversion and writes nothing (fields to MEDIT: $rc)"
cp "$dir/m.vmsh" "$dir/m_keep.vmsh"
"$conv" --strict --format medit "$dir/m_keep.vmsh" "$dir/m_keep.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 3 ] && cmp -s "$dir/m.vmsh" "$dir/m_keep.vmsh"' "--strict with OUT == IN: exit 3, the input intact (it was replaced by the lossy STL: $rc)"
check 'grep -q "m_keep.vmsh: " "$dir/err" && ! grep -q "vm-convert-strict" "$dir/err"' "the warnings name OUT, not the trial: $(head -1 "$dir/err")"
"$conv" --strict "$dir/m.vmsh" "$dir/m_err.stl" 2>"$dir/err"
check 'grep -q "m_err.stl" "$dir/err" && ! grep -q "vm-convert-strict" "$dir/err"' "an error of the trial names OUT: $(head -1 "$dir/err")"
"$conv" --strict -q "$dir/m.vmsh" "$dir/m_strict.vtu"
check '[ $? -eq 0 ] && [ -s "$dir/m_strict.vtu" ]' "--strict writes a lossless conversion"
"$conv" --version | grep -q "vm-convert (varmesh)"
check '[ $? -eq 0 ]' "--version"
"$qual" --help | grep -q "require-valid"
check '[ $? -eq 0 ]' "vm-quality --help"
exit $fail
