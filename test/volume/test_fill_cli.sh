#!/usr/bin/env bash
# test/volume/test_fill_cli.sh: vm-fill end to end on a closed surface and
# on bad input. A sphere's surface filled to a far field: exit 0, stdout
# only the JSON summary (Gmsh's own messages never reach stdout), the
# surface's vertices bit-identical in the output. Bad input (a missing
# file, an open surface, two overlapping spheres given as one surface, a
# far field that cuts the model, a hexahedral layer): one line on stderr,
# exit 1, no output file, no temporary file (Gmsh aborting at every try:
# the two fallbacks' warnings before that line).
# Usage errors: exit 2. Gmsh aborting at its first two tries (injected by
# VM_FILL_GMSH_ABORT): the fill meshes again without the points off the
# envelope, then with the envelope in reverse order, and succeeds.
set -u
gen=$1 fill=$2 conv=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
nothing_left() { [ -z "$(ls -A "$dir/out" 2>/dev/null)" ]; }
mkdir -p "$dir/out"

"$gen" sphere --level 2 "$dir/s.vmsh"
"$fill" --json --farfield 5 "$dir/s.vmsh" "$dir/out/f.vmsh" >"$dir/stdout" 2>"$dir/stderr"
rc=$?
check '[ $rc -eq 0 ] && [ -s "$dir/out/f.vmsh" ]' "a sphere's surface filled (exit $rc)"
check '[ "$(wc -l <"$dir/stdout")" -eq 1 ] && grep -q "^{\"input\": .*\"tets\": [1-9]" "$dir/stdout"' "stdout holds the JSON summary and nothing else"
check 'grep -q "envelope 320 triangles kept exactly" "$dir/stderr"' "stderr says the envelope was kept: $(tail -1 "$dir/stderr")"
"$conv" "$dir/s.vmsh" "$dir/s.vmsht" 2>/dev/null && "$conv" "$dir/out/f.vmsh" "$dir/f.vmsht" 2>/dev/null
n=$(sed -n 's/^vertices //p' "$dir/s.vmsht")
check '[ -n "$n" ] && diff <(sed -n "/^vertices/,+${n}p" "$dir/s.vmsht" | tail -n +2 | cut -d" " -f1-3) <(sed -n "/^vertices/,+${n}p" "$dir/f.vmsht" | tail -n +2 | cut -d" " -f1-3) >/dev/null' "the surface's $n vertices come first, bit-identical"
rm -f "$dir/out/"*
"$fill" -q "$dir/s.vmsh" "$dir/out/f.vmsh" >"$dir/stdout" 2>"$dir/stderr"
check '[ $? -eq 0 ] && [ ! -s "$dir/stdout" ] && [ ! -s "$dir/stderr" ]' "-q: nothing on stdout or stderr"
rm -f "$dir/out/"*

# Gmsh's process aborts twice (as its boundary recovery does on some
# envelopes): the third try, the envelope given in reverse order, meshes
# it, and the surface is still kept bit for bit
VM_FILL_GMSH_ABORT=2 "$fill" --farfield 5 "$dir/s.vmsh" "$dir/out/f.vmsh" >/dev/null 2>"$dir/stderr"
rc=$?
check '[ $rc -eq 0 ] && grep -q "VM_FILL_GMSH_ABORT: aborted; meshing again without the points off the envelope" "$dir/stderr" && grep -q "VM_FILL_GMSH_ABORT: aborted; meshing again with the envelope given in reverse order" "$dir/stderr" && grep -q "envelope 320 triangles kept exactly" "$dir/stderr"' "Gmsh aborting twice: meshed at the third try, in reverse order (exit $rc)"
"$conv" "$dir/out/f.vmsh" "$dir/f.vmsht" 2>/dev/null
check '[ -n "$n" ] && diff <(sed -n "/^vertices/,+${n}p" "$dir/s.vmsht" | tail -n +2 | cut -d" " -f1-3) <(sed -n "/^vertices/,+${n}p" "$dir/f.vmsht" | tail -n +2 | cut -d" " -f1-3) >/dev/null' "... the surface's $n vertices bit-identical there too"
rm -f "$dir/out/"*

bad() { # name expected-substring args...
  local name=$1 want=$2
  shift 2
  "$fill" -q "$@" "$dir/out/f.vmsh" >"$dir/stdout" 2>"$dir/stderr"
  local rc=$?
  check '[ $rc -eq 1 ] && [ "$(wc -l <"$dir/stderr")" -eq 1 ] && grep -q -- "$want" "$dir/stderr" && [ ! -s "$dir/stdout" ] && nothing_left' "$name: exit 1, one line, no output (exit $rc: $(cat "$dir/stderr"))"
  rm -f "$dir/out/"* "$dir/out/".* 2>/dev/null
}
bad "missing file" "no-such" "$dir/no-such.vmsh"
printf 'solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n' >"$dir/one.stl"
bad "an open surface" "not closed" "$dir/one.stl"
# two unit spheres 0.5 apart, as one surface: it intersects itself
"$conv" "$dir/s.vmsh" "$dir/s.off" 2>/dev/null
awk 'NR == 1 { next } NR == 2 { split($0, h); nv = h[1]; nf = h[2]; next }
     NR <= 2 + nv { v[NR - 2] = $0; next } NR <= 2 + nv + nf { f[NR - 2 - nv] = $0 }
     END { print "OFF"; print 2 * nv, 2 * nf, 0
           for (i = 1; i <= nv; i++) print v[i]
           for (i = 1; i <= nv; i++) { split(v[i], p); print p[1] + 0.5, p[2], p[3] }
           for (i = 1; i <= nf; i++) print f[i]
           for (i = 1; i <= nf; i++) { split(f[i], q); print 3, q[2] + nv, q[3] + nv, q[4] + nv } }' \
  "$dir/s.off" >"$dir/two.off"
bad "a surface that intersects itself" "intersect" "$dir/two.off"
bad "a far field that cuts the model" "far field" --farfield 0.5 "$dir/s.vmsh"
"$gen" rotcube --n 3 "$dir/h.vmsh"
bad "a hexahedral mesh (one boundary, quadrilaterals)" "quadrilaterals" "$dir/h.vmsh"
# Gmsh aborting at every try: the two fallbacks said as warnings, then
# one error line, exit 1, no output
VM_FILL_GMSH_ABORT=3 "$fill" "$dir/s.vmsh" "$dir/out/f.vmsh" >"$dir/stdout" 2>"$dir/stderr"
rc=$?
check '[ $rc -eq 1 ] && [ "$(grep -c "error" "$dir/stderr")" -eq 1 ] && tail -1 "$dir/stderr" | grep -q "error: .*Gmsh crashed (signal 6): VM_FILL_GMSH_ABORT: aborted$" && [ "$(grep -c "warning: fill: Gmsh crashed" "$dir/stderr")" -eq 2 ] && [ ! -s "$dir/stdout" ] && nothing_left' "Gmsh aborting at every try: two fallbacks, then one error line, exit 1, no output (exit $rc: $(tail -1 "$dir/stderr"))"
rm -f "$dir/out/"* "$dir/out/".* 2>/dev/null

"$fill" --refine 1,2,3 "$dir/s.vmsh" "$dir/out/f.vmsh" 2>/dev/null
check '[ $? -eq 2 ] && nothing_left' "--refine with 3 numbers: usage error"
"$fill" --growth 0.5 "$dir/s.vmsh" "$dir/out/f.vmsh" 2>/dev/null
check '[ $? -eq 2 ] && nothing_left' "--growth 0.5: usage error"
"$fill" --refine -1,-1,-1,1,1,1,0.2 --farfield 4 -q "$dir/s.vmsh" "$dir/out/r.vmsh"
check '[ $? -eq 0 ] && [ -s "$dir/out/r.vmsh" ] && [ $(stat -c %s "$dir/out/r.vmsh") -gt 0 ]' "--refine box: runs"
exit $fail
