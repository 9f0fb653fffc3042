#!/usr/bin/env bash
# test/cli/test_empty.sh: an empty mesh is an error for every stage and
# every requested check, and a file with no record of its format is bad
# input (issue 21, item 8: any .obj that was not an OBJ read as an empty
# mesh with exit 0; zero-triangle STL, OFF and PLY files passed
# vm-quality --require-valid --verify).
# usage: test_empty.sh VM_CONVERT VM_QUALITY VM_GEN VM_PRISM VM_SURFACE VM_VOLUME [VM_FILL]
set -u
conv=$1 qual=$2 gen=$3
shift 3
stages=("$@")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
head -c 4096 /dev/urandom >"$dir/random.obj"
"$gen" sphere --level 1 "$dir/s.vmsh" && cp "$dir/s.vmsh" "$dir/renamed.obj"
for f in random renamed; do
  err=$("$conv" "$dir/$f.obj" "$dir/o.vmsh" 2>&1)
  rc=$?
  check '[ $rc -eq 1 ] && [ ! -e "$dir/o.vmsh" ] && grep -q "not an OBJ file" <<<"$err" && [ $(wc -l <<<"$err") -eq 1 ]' "$f bytes as .obj: bad input (exit $rc: $err)"
done
printf 'solid x\nendsolid x\n' >"$dir/e.stl"
printf 'OFF\n0 0 0\n' >"$dir/e.off"
printf 'ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n' >"$dir/e.ply"
for f in e.stl e.off e.ply; do
  "$qual" --require-valid --verify "$dir/$f" >/dev/null 2>"$dir/err"
  rc=$?
  check '[ $rc -ne 0 ] && grep -q "no elements" "$dir/err"' "vm-quality --require-valid --verify $f: an error, not a pass (exit $rc)"
  for s in "${stages[@]}"; do
    "$s" -q "$dir/$f" "$dir/o.vmsh" 2>/dev/null
    rc=$?
    check '[ $rc -ne 0 ] && [ ! -e "$dir/o.vmsh" ]' "$(basename "$s") $f: an error, nothing written (exit $rc)"
  done
done
exit $fail
