#!/usr/bin/env bash
# test/verify/test_verify_cli.sh VM_GEN VM_CONVERT VM_QUALITY: vm-quality
# --verify on files written by vm-gen / vm-convert and by hand: exit 0 for
# valid meshes, exit 3 with a one-line message naming the first bad element
# for an inverted tet, a tangled cube and two prisms whose tops cross.
set -u
gen=$1 convert=$2 quality=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
# expect CODE PATTERN CMD...: exit code CODE and stderr matching PATTERN
# (an empty PATTERN matches anything)
expect() {
  local want=$1 pat=$2
  shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"
  local rc=$?
  local okpat=1
  if [ -n "$pat" ]; then grep -q -- "$pat" "$tmp/err" || okpat=0; fi
  if [ "$rc" -ne "$want" ] || [ "$okpat" -eq 0 ]; then
    echo "FAIL: $* -> exit $rc (want $want), stderr:" >&2
    cat "$tmp/err" >&2
    fail=1
  else
    echo "ok: $* -> exit $rc"
  fi
}

"$gen" rotcube --n 4 "$tmp/hex.vmsh" || fail=1
"$gen" rotcube --n 3 --mixed "$tmp/mixed.vmsh" || fail=1
"$gen" rotcube --n 4 --tets "$tmp/tets.vmsh" || fail=1
"$gen" rotcube --n 6 --angle pi/2 "$tmp/tangled.vmsh" || fail=1
"$convert" -q "$tmp/hex.vmsh" "$tmp/hex.vtu" || fail=1
"$convert" -q "$tmp/mixed.vmsh" "$tmp/mixed.msh" || fail=1

expect 0 "" "$quality" -q --verify "$tmp/hex.vmsh"
expect 0 "" "$quality" -q --verify --rule geometric "$tmp/hex.vmsh"
expect 0 "" "$quality" -q --verify "$tmp/hex.vtu"
expect 0 "" "$quality" -q --verify --rule geometric "$tmp/mixed.msh"
grep -q "^verify: every quadrature simplex (geometric rule) positively oriented (exact), every cell certified det J > 0; prism layer" \
  "$tmp/out" || { echo "FAIL: no verify line for mixed.msh" >&2; fail=1; }
expect 0 "" "$quality" -q --verify --json "$tmp/tets.vmsh"
python3 -m json.tool "$tmp/out" >/dev/null || { echo "FAIL: --verify --json: not JSON" >&2; fail=1; }
expect 3 "verify: element [0-9]* (hex)" "$quality" -q --verify "$tmp/tangled.vmsh"

# one tet of three listed with its base reversed
cat >"$tmp/inverted.vmsht" <<'MESH'
vmsht 1 0
dim 3
vertices 6
0 0 0 free -1
1 0 0 free -1
0 1 0 free -1
0 0 1 free -1
1 1 1 free -1
-1 -1 -1 free -1
elements 3
tet 0 1 2 3
tet 0 2 1 4
tet 0 2 1 5
fields 0
attributes 0
end
MESH
expect 3 "verify: element 1 (tet)" "$quality" -q --verify "$tmp/inverted.vmsht"
[ "$(wc -l <"$tmp/err")" -eq 1 ] || { echo "FAIL: message is not one line" >&2; fail=1; }

# two prisms on the plate z = 0 whose tilted tops cross
cat >"$tmp/crossing.vmsht" <<'MESH'
vmsht 1 0
dim 3
vertices 12
0 0 0 fixed -1
1 0 0 fixed -1
0 1 0 fixed -1
2 0 0 fixed -1
3 0 0 fixed -1
2 1 0 fixed -1
1.5 0 1 free -1
2.5 0 1.6 free -1
1.5 1 1 free -1
1.2 0 1.4 free -1
2.2 0 1 free -1
1.2 1 1.4 free -1
elements 2
prism 0 1 2 6 7 8
prism 3 4 5 9 10 11
fields 0
attributes 0
end
MESH
expect 3 "verify: prisms 0 and 1: outer faces intersect" "$quality" -q --verify \
  "$tmp/crossing.vmsht"
sed 's/^1.2 0 1.4 free/1.2 0 2.4 free/; s/^2.2 0 1 free/2.2 0 2 free/; s/^1.2 1 1.4 free/1.2 1 2.4 free/' \
  "$tmp/crossing.vmsht" >"$tmp/apart.vmsht"
expect 0 "" "$quality" -q --verify "$tmp/apart.vmsht"
exit $fail
