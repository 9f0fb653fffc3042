#!/usr/bin/env bash
# test/run.sh: build varmesh and run its whole test suite; the last line is
# "N passed, N failed". Options: --sanitize (ASan+UBSan build in
# build-sanitize/), any other arguments go to `meson test`.
set -u
root=$(cd "$(dirname "$0")/.." && pwd)
build="$root/build"
setup_args=()
test_args=()
if [ "${1:-}" = "--sanitize" ]; then
  shift
  build="$root/build-sanitize"
  setup_args=(-Dsanitize=true)
  export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
  export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export LSAN_OPTIONS=suppressions=$root/test/lsan.supp:print_suppressions=0
  test_args=(--timeout-multiplier 6) # instrumented code runs several times slower
fi
# two tests run at once on a 2-core machine: OpenMP threads that spin while
# they wait would steal the other test's core (measured: 3x the CPU time)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
if [ ! -f "$build/build.ninja" ]; then
  meson setup "$build" "$root" "${setup_args[@]}" >"$build.setup.log" 2>&1 || {
    cat "$build.setup.log"; echo "0 passed, 1 failed"; exit 1; }
fi
if ! ninja -C "$build" >"$build.ninja.log" 2>&1; then
  tail -n 60 "$build.ninja.log"
  echo "0 passed, 1 failed"
  exit 1
fi
meson test -C "$build" --print-errorlogs --num-processes 2 "${test_args[@]}" "$@" | tee "$build.test.log"
rc=${PIPESTATUS[0]}
count() { awk -v k="$1" '$0 ~ "^"k":" {print $NF}' "$build.test.log" | tail -n 1; }
ok=$(count "Ok"); xf=$(count "Expected Fail"); fail=$(count "Fail")
up=$(count "Unexpected Pass"); to=$(count "Timeout"); sk=$(count "Skipped")
passed=$(( ${ok:-0} + ${xf:-0} ))
failed=$(( ${fail:-0} + ${up:-0} + ${to:-0} ))
if [ "$rc" -ne 0 ] && [ "$failed" -eq 0 ]; then failed=1; fi
# the last line is always exactly "N passed, N failed"
if [ "${sk:-0}" -gt 0 ]; then echo "(${sk} skipped: see the log above)"; fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
