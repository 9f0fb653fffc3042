#!/usr/bin/env bash
# test/cli/test_threads.sh: --threads is checked against the machine (at
# most 4 a core): 65,536 threads crashed libgomp (exit 139) in vm-prism,
# vm-surface and vm-volume, and 32,768 failed with libgomp's own message.
# Every program with the option: a usage error (exit 2) naming it beyond
# the limit, accepted within it.
set -u
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
cores=$(getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)
for prog in "$@"; do
  name=$(basename "$prog")
  "$prog" --list-options 2>/dev/null | grep -qx -- --threads || continue
  for n in 65536 32768 $((4 * cores + 1)); do
    out=$("$prog" --threads $n /nonexistent.vmsh /tmp/out.vmsh 2>&1)
    rc=$?
    check '[ $rc -eq 2 ] && grep -q -- "--threads" <<<"$out"' "$name --threads $n: usage error (exit $rc: $out)"
  done
  out=$("$prog" --threads $((4 * cores)) /nonexistent.vmsh /tmp/out.vmsh 2>&1)
  rc=$?
  check '[ $rc -eq 1 ]' "$name --threads $((4 * cores)) accepted (then the missing input: exit $rc)"
done
exit $fail
