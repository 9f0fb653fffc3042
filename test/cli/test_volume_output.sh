#!/usr/bin/env bash
# test/cli/test_volume_output.sh: a stage whose result is a volume mesh
# refuses an output format that holds surfaces only (STL, OBJ, OFF, PLY):
# vm-prism wrote one, dropping every prism with a warning, exited 0 and
# with OUT == IN replaced its input wall (issue 21, item 4). Exit 2,
# nothing written, the input intact.
# usage: test_volume_output.sh VM_GEN VM_PRISM VM_VOLUME [VM_FILL]
set -u
gen=$1 prism=$2 vol=$3 fill=${4:-}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$gen" sphere --level 1 "$dir/s.stl" && "$gen" rotcube --n 3 "$dir/c.vmsh"
cp "$dir/s.stl" "$dir/s0.stl"
progs=("$prism" "$vol")
ins=("$dir/s.stl" "$dir/c.vmsh")
if [ -n "$fill" ]; then progs+=("$fill"); ins+=("$dir/s.stl"); fi
for i in "${!progs[@]}"; do
  p=${progs[$i]} in=${ins[$i]} name=$(basename "${progs[$i]}")
  for ext in stl obj off ply; do
    err=$("$p" -q "$in" "$dir/out.$ext" 2>&1)
    rc=$?
    check '[ $rc -eq 2 ] && [ ! -e "$dir/out.$ext" ] && grep -q "surfaces only" <<<"$err"' "$name to .$ext: usage error, nothing written (exit $rc)"
  done
done
"$prism" -q "$dir/s.stl" "$dir/s.stl" 2>/dev/null
rc=$?
check '[ $rc -eq 2 ] && cmp -s "$dir/s.stl" "$dir/s0.stl"' "vm-prism s.stl s.stl: refused, the input intact (exit $rc)"
"$prism" -q --format stl "$dir/s.stl" "$dir/out.vmsh" 2>/dev/null
check '[ $? -eq 2 ] && [ ! -e "$dir/out.vmsh" ]' "vm-prism --format stl: refused"
exit $fail
