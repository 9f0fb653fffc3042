#!/usr/bin/env bash
# test/cli/test_hostile.sh: issue 21, item 11. A FIFO as input is refused at
# once (it blocked forever: the regular-file check came after fopen); bytes
# from a file quoted in a message reach the terminal escaped (escape
# sequences in the vtk, msh, medit and vmsht readers' messages drove it);
# a PLY face index of a float type must be a whole number (1.7 was read
# as 1).
# usage: test_hostile.sh VM_CONVERT
set -u
conv=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
mkfifo "$dir/fifo.stl"
err=$(timeout 10 "$conv" "$dir/fifo.stl" "$dir/o.vmsh" 2>&1)
rc=$?
check '[ $rc -eq 1 ] && grep -q "not a regular file" <<<"$err"' "a FIFO as input: refused at once (exit $rc: $err)"
printf '# vtk DataFile Version 3.0\nx\nASCII\nDATASET \033[31mRED\033]0;title\007\n' >"$dir/esc.vtk"
printf 'vmsht 1 0\ndim 3\nvertices 1\n0 0 0 free \033[2J -1\n' >"$dir/esc.vmsht"
printf '$MeshFormat\n\033[31m 0 8\n$EndMeshFormat\n' >"$dir/esc.msh"
printf 'MeshVersionFormatted 2\nDimension \033[5m\n' >"$dir/esc.mesh"
for f in esc.vtk esc.vmsht esc.msh esc.mesh; do
  "$conv" "$dir/$f" "$dir/o.vmsh" 2>"$dir/err"
  rc=$?
  check '[ $rc -eq 1 ] && ! grep -q $'"'"'[\x01-\x08\x0b-\x1f\x7f]'"'"' "$dir/err" && [ $(wc -l <"$dir/err") -eq 1 ]' "$f: one line, no control byte on stderr (exit $rc: $(cat -v "$dir/err"))"
done
ply() { # the index list's type, a face's line
  printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar %s vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n%s\n' "$1" "$2"
}
ply float "3 0 1.7 2" >"$dir/f.ply"
err=$("$conv" "$dir/f.ply" "$dir/o.vmsh" 2>&1)
check '[ $? -eq 1 ] && grep -q "bad vertex index 1.7" <<<"$err"' "PLY float index 1.7: refused ($err)"
ply float "3 0 1 2" >"$dir/g.ply"
"$conv" -q "$dir/g.ply" "$dir/o.vmsh"
check '[ $? -eq 0 ] && [ -s "$dir/o.vmsh" ]' "PLY float indices that are whole numbers: read"
exit $fail
