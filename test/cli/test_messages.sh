#!/usr/bin/env bash
# test/cli/test_messages.sh: honest exits and messages (issue 21, item 14):
# a legal 245-byte output name works (the temporary name no longer
# overflows NAME_MAX); a write failure says why (strerror, CGNS too); a --report that
# fails half-way (no space) leaves no report directory; Ctrl-C during
# vm-surface's remeshing exits 4 (was 130); vm-gen --angle nan is a usage
# error; vm-volume names the file and says what a collapsed hex and an
# overflowing volume are; vm-surface does not call an overflow a zero
# area; vm-prism counts non-manifold edges as the reader does; -v adds
# the debug lines and changes nothing else.
# usage: test_messages.sh VM_GEN VM_CONVERT VM_QUALITY VM_VOLUME VM_SURFACE VM_PRISM
set -u
gen=$1 conv=$2 qual=$3 vol=$4 surf=$5 prism=$6
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
cd "$dir" || exit 1
"$gen" sphere --level 1 s.vmsh && "$gen" sphere --level 4 s4.vmsh || exit 1

long=$(printf 'a%.0s' $(seq 240)).vmsh # 245 bytes: legal
"$gen" sphere --level 1 "$long" 2>err
rc=$?
check '[ $rc -eq 0 ] && [ -s "$long" ] && [ $(ls | wc -l) -eq 4 ]' "vm-gen writes a 245-byte file name, no temporary left (exit $rc: $(cat err))"
rm -f "$long"

for ext in vmsh su2 stl obj off ply vtk; do
  (ulimit -f 8; trap '' XFSZ; "$conv" s4.vmsh "w.$ext" 2>err)
  rc=$?
  check '[ $rc -eq 1 ] && grep -q "write failed: File too large" err && [ ! -e "w.$ext" ]' "a failed .$ext write says why (exit $rc: $(cat err))"
done
# CGNS (when built): libcgns's message and the system's reason; no crash in
# HDF5's exit handler (it segfaulted on the file whose close had failed) and
# no temporary file left
if "$conv" s.vmsh c.cgns 2>/dev/null; then
  (ulimit -f 8; trap '' XFSZ; "$conv" s4.vmsh w.cgns 2>err)
  rc=$?
  check '[ $rc -eq 1 ] && grep -q "libcgns: .*write failed: File too large" err && [ $(wc -l <err) -eq 1 ] && [ -z "$(ls | grep "^w\.cgns")" ]' "a failed .cgns write says why, exit 1, nothing left (exit $rc: $(cat err))"
  rm -f c.cgns
fi

(ulimit -f 20; trap '' XFSZ; "$qual" --report R s4.vmsh >/dev/null 2>err)
rc=$?
check '[ $rc -eq 1 ] && [ ! -e R ] && [ -z "$(ls -A | grep vmreport)" ]' "a --report that fails for space leaves no report directory (exit $rc: $(cat err))"
"$qual" --report R s.vmsh >/dev/null 2>err
check '[ -s R/index.html ] && [ -s R/quality.png ] && [ -z "$(ls -A R | grep tmp)" ]' "... and one that does not fail is complete"

"$gen" sphere --level 5 s5.vmsh || exit 1
"$surf" remesh -q --target-edge-length 0.02 s5.vmsh r.vmsh 2>err &
pid=$!
sleep 1
kill -INT $pid
wait $pid
rc=$?
check '[ $rc -eq 4 ] && [ -s r.vmsh ]' "Ctrl-C during vm-surface's remeshing: exit 4, the mesh written (exit $rc: $(cat err))"

"$gen" rotcube --angle nan x.vmsh 2>err
rc=$?
check '[ $rc -eq 2 ] && [ ! -e x.vmsh ]' "vm-gen --angle nan: a usage error (exit $rc)"

"$gen" rotcube --n 2 --angle 0.3 rc.vmsht || exit 1
awk '$1 == "elements" { d = 1; print; next } d == 1 && $1 == "hex" { $3 = $2; d = 2 } { print }' rc.vmsht >col.vmsht
"$vol" -q col.vmsht o.vmsh 2>err
rc=$?
check '[ $rc -eq 1 ] && grep -q "col.vmsht: element 0 (hex) uses vertex 0 at two of its corners: a collapsed element" err' "vm-volume: a collapsed hex named with the file (exit $rc: $(cat err))"
scale='$1 == "vertices" { n = $2; print; next } n > 0 && k < n { k++; $1 *= 1e200; $2 *= 1e200; $3 *= 1e200 } { print }'
awk "$scale" rc.vmsht >big.vmsht
"$vol" -q big.vmsht o.vmsh 2>err
rc=$?
check '[ $rc -eq 1 ] && grep -q "big.vmsht: the mesh volume overflows" err && ! grep -q "nan\|inf" err' "vm-volume: an overflowing volume said so (exit $rc: $(cat err))"
"$gen" sphere --level 1 sp.vmsht && awk "$scale" sp.vmsht >spbig.vmsht
for step in adapt all; do
  "$surf" $step -q spbig.vmsht o.vmsh 2>err
  rc=$?
  check '[ $rc -eq 1 ] && grep -q "overflows double precision" err && ! grep -q "zero.area" err' "vm-surface $step: an overflow is not a zero area (exit $rc: $(cat err))"
done

# two tetrahedra on one edge: four faces on it, one non-manifold edge
cat >fin.obj <<'OBJ'
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
v 0 -1 0
v 0 0 -1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
f 1 5 6
f 1 2 5
f 1 6 2
f 2 6 5
OBJ
"$conv" fin.obj fin.vmsh 2>err.read
"$prism" -q fin.obj o.vmsh 2>err
rc=$?
check '[ $rc -eq 1 ] && grep -q " 1 edges are shared by more than two faces" err.read && grep -q " 1 edges are shared by more than two triangles" err' "vm-prism counts non-manifold edges as the reader does (exit $rc: $(cat err.read err))"
# -v shows the debug messages (the prism stage's relief sweeps), -q and the
# default do not
"$gen" sphere --level 2 ball.vmsh || exit 1
"$prism" -v -t 0.2 -n 3 ball.vmsh b.vmsh 2>err.v
rc=$?
"$prism" -t 0.2 -n 3 ball.vmsh b2.vmsh 2>err.d
check '[ $rc -eq 0 ] && grep -q "non-orthogonality relief sweep 1:" err.v && ! grep -q "relief sweep" err.d && cmp -s b.vmsh b2.vmsh' "vm-prism -v adds the debug lines, nothing else changes (exit $rc)"
exit $fail
