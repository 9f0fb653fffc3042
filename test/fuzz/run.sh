#!/usr/bin/env bash
# test/fuzz/run.sh [SECONDS] [READER...]: run each reader fuzzer (built by
# build.sh) for SECONDS (default 60), one after the other. New inputs go to
# build-fuzz/work/<reader>/ (the seed corpus in test/fuzz/corpus/ is only
# read); crashes, hangs and OOMs to build-fuzz/artifacts/<reader>/. Prints
# one summary line per reader; exit 1 if any reader left an artifact.
# Environment: FUZZ_DIR (default build-fuzz: where the binaries are);
# FUZZ_CPU=1: SECONDS is a budget of CPU seconds, not wall seconds (on a
# shared machine a wall-clock budget buys little work): the fuzzer is
# interrupted once its user + system time reaches it (wall cap: FUZZ_WALL
# seconds, default 10 x SECONDS).
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
secs=${1:-60}
[ $# -gt 0 ] && shift
readers=${*:-vmsh vmsht vtk vtu msh medit stl obj off ply su2 cgns}
bin=${FUZZ_DIR:-$root/build-fuzz}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
# third-party leaks by design (libcgns on malformed files): test/lsan.supp
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/test/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
bad=0
for r in $readers; do
  exe="$bin/fuzz-$r"
  [ -x "$exe" ] || { echo "run.sh: $exe missing: run test/fuzz/build.sh first" >&2; exit 2; }
  work="$bin/work/$r" art="$bin/artifacts/$r"
  mkdir -p "$work" "$art" "$here/regress/$r"
  dict=()
  [ -f "$here/dict/$r.dict" ] && dict=(-dict="$here/dict/$r.dict")
  log="$bin/fuzz-$r.log"
  t0=$(date +%s)
  # CPU seconds of the fuzzer (user + system): on a loaded machine the wall
  # time overstates the work done
  wall=$secs
  [ "${FUZZ_CPU:-0}" = 1 ] && wall=${FUZZ_WALL:-$((10 * secs))}
  cpu=$( { TIMEFORMAT='%U %S'; time {
    "$exe" "$work" "$here/corpus/$r" "$here/regress/$r" \
      "${dict[@]}" -max_total_time="$wall" -rss_limit_mb=2048 -malloc_limit_mb=512 \
      -timeout=10 -max_len=65536 -print_final_stats=1 -artifact_prefix="$art/" >"$log" 2>&1 &
    pid=$!
    if [ "${FUZZ_CPU:-0}" = 1 ]; then
      # watchdog: SIGTERM (libFuzzer prints its final stats) at the CPU budget
      tck=$(getconf CLK_TCK)
      while kill -0 "$pid" 2>/dev/null; do
        used=$(awk -v t="$tck" '{sub(/^.*\) /, ""); print int(($12 + $13) / t)}' \
          "/proc/$pid/stat" 2>/dev/null)
        [ "${used:-0}" -ge "$secs" ] && { stopped=1; kill -TERM "$pid"; break; }
        sleep 2
      done
    fi
    wait "$pid"
    st=$?
    # 72: libFuzzer's exit code when interrupted, here by the watchdog
    [ "$st" = 72 ] && [ "${stopped:-0}" = 1 ] && st=0
    echo "rc $st" >"$log.rc"; }; } 2>&1 | awk '{printf "%.0f", $1 + $2}')
  rc=$(awk '{print $2}' "$log.rc")
  t1=$(date +%s)
  execs=$(awk '/stat::number_of_executed_units/ {print $2}' "$log" | tail -n 1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | awk '{print $2}')
  found=$(find "$art" -type f | wc -l)
  printf "run.sh: %-6s %5d s wall %5d s cpu  rc %d  execs %s  cov %s  corpus %d  artifacts %d\n" \
    "$r" $((t1 - t0)) "$cpu" "$rc" "${execs:-?}" "${cov:-?}" "$(find "$work" -type f | wc -l)" "$found"
  if [ "$found" -gt 0 ] || [ "$rc" -ne 0 ]; then
    bad=1
    find "$art" -type f | sed 's/^/run.sh:   /'
  fi
done
exit $bad
