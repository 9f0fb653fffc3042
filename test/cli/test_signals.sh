#!/usr/bin/env bash
# test/cli/test_signals.sh: no program leaves a temporary file on a signal
# (issue 21, item 1: a second SIGINT while a stage was writing left
# OUT.tmp.PID.N; vm-convert and vm-gen did not catch signals and left one
# on the first). Each program is signalled at a range of moments of its
# run (before, during and after writing); afterwards the output is absent
# or complete and no OUT.tmp.* exists.
# usage: test_signals.sh VM_GEN VM_CONVERT VM_VOLUME
set -u
gen=$1 conv=$2 vol=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$gen" rotcube --n 60 "$dir/big.vmsh"
"$conv" "$dir/big.vmsh" "$dir/ref.vtk" 2>/dev/null
size=$(stat -c %s "$dir/ref.vtk")
left() { ls -A "$dir/out" | grep -c "\.tmp\." ; }
n=0
for delay in 0.02 0.05 0.1 0.15 0.2 0.3 0.4 0.6; do
  for sig in INT TERM HUP; do
    rm -rf "$dir/out" && mkdir "$dir/out"
    "$conv" "$dir/big.vmsh" "$dir/out/o.vtk" 2>/dev/null &
    pid=$!
    sleep $delay
    kill -$sig $pid 2>/dev/null
    wait $pid
    rc=$?
    t=$(left)
    ok=1
    [ "$t" -eq 0 ] || ok=0
    if [ -e "$dir/out/o.vtk" ] && [ "$(stat -c %s "$dir/out/o.vtk")" -ne "$size" ]; then ok=0; fi
    [ $ok -eq 1 ] || { echo "FAIL: vm-convert SIG$sig after ${delay}s: exit $rc, $t temporary files, output $(ls -la "$dir/out")"; fail=1; }
    n=$((n + 1))
  done
done
check '[ $fail -eq 0 ]' "vm-convert signalled at $n moments: never a temporary file, the output absent or complete"
# a stage: the first signal stops it at a safe point (it writes its best
# mesh), a second one at once ends it without a temporary file
"$gen" rotcube --n 24 --angle pi "$dir/t.vmsh"
bad=0
for delay in 0.3 0.6 1.0 1.5; do
  rm -rf "$dir/out" && mkdir "$dir/out"
  "$vol" -q "$dir/t.vmsh" "$dir/out/o.vtk" 2>/dev/null &
  pid=$!
  sleep $delay
  kill -INT $pid 2>/dev/null
  sleep 0.05
  kill -INT $pid 2>/dev/null
  wait $pid
  t=$(left)
  [ "$t" -eq 0 ] || { echo "FAIL: vm-volume double SIGINT after ${delay}s: $t temporary files"; bad=1; }
done
check '[ $bad -eq 0 ]' "vm-volume interrupted twice: never a temporary file"
exit $fail
