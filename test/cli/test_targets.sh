#!/usr/bin/env bash
# test/cli/test_targets.sh: what is at the output path is respected (issue
# 21, item 2; the writers renamed a temporary file onto the path without
# looking): a character device is written through and stays a device
# (mknod null c 1 3 became a regular file); a symbolic link stays a link
# and its target is written (a dangling one too); a 0600 file keeps its
# mode (it became 0644); a read-only file is refused, not replaced; "-"
# writes to standard output.
# usage: test_targets.sh VM_GEN VM_CONVERT
set -u
gen=$1 conv=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$gen" sphere --level 1 "$dir/s.vmsh"
if mknod "$dir/null" c 1 3 2>/dev/null; then
  "$conv" -q "$dir/s.vmsh" "$dir/null" --format vtk
  check '[ $? -eq 0 ] && [ -c "$dir/null" ]' "a character device is written through and stays one"
else
  echo "skip: mknod needs root"
fi
printf x >"$dir/t.vtk" && ln -s t.vtk "$dir/l.vtk"
"$conv" -q "$dir/s.vmsh" "$dir/l.vtk"
check '[ $? -eq 0 ] && [ -L "$dir/l.vtk" ] && [ $(stat -c %s "$dir/t.vtk") -gt 1 ]' "a symbolic link stays, its target is written"
ln -s new.vtk "$dir/d.vtk"
"$conv" -q "$dir/s.vmsh" "$dir/d.vtk"
check '[ $? -eq 0 ] && [ -L "$dir/d.vtk" ] && [ -s "$dir/new.vtk" ]' "a dangling link: its target is created"
printf x >"$dir/m.vtk" && chmod 0600 "$dir/m.vtk"
"$conv" -q "$dir/s.vmsh" "$dir/m.vtk"
rc=$?
check '[ $rc -eq 0 ] && [ "$(stat -c %a "$dir/m.vtk")" = 600 ]' "a 0600 file keeps its mode ($(stat -c %a "$dir/m.vtk"))"
printf x >"$dir/r.vtk" && chmod 0444 "$dir/r.vtk"
"$conv" -q "$dir/s.vmsh" "$dir/r.vtk" 2>"$dir/err"
check '[ $? -eq 1 ] && [ "$(cat "$dir/r.vtk")" = x ] && grep -q "read-only" "$dir/err"' "a read-only file is refused, not replaced"
"$conv" -q "$dir/s.vmsh" - --format stl >"$dir/out.stl"
check '[ $? -eq 0 ] && head -1 "$dir/out.stl" | grep -q "^solid" && [ -z "$(ls "$dir" | grep -- "^-")" ]' "'-' writes to standard output"
check '[ -z "$(ls -A "$dir" | grep "\.tmp\.")" ]' "no temporary file left"
exit $fail
