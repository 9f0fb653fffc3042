#!/usr/bin/env bash
# test/fuzz/run.sh [SECONDS] [READER...]: run each reader fuzzer (built by
# build.sh) for SECONDS (default 60), one after the other. New inputs go to
# build-fuzz/work/<reader>/ (the seed corpus in test/fuzz/corpus/ is only
# read); crashes, hangs and OOMs to build-fuzz/artifacts/<reader>/. Prints
# one summary line per reader; exit 1 if any reader left an artifact.
# Environment: FUZZ_DIR (default build-fuzz: where the binaries are).
set -u
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
secs=${1:-60}
[ $# -gt 0 ] && shift
readers=${*:-vmsh vmsht vtk vtu msh medit stl obj off ply}
bin=${FUZZ_DIR:-$root/build-fuzz}
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0}
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
  cpu=$( { TIMEFORMAT='%U %S'; time "$exe" "$work" "$here/corpus/$r" "$here/regress/$r" \
    "${dict[@]}" -max_total_time="$secs" -rss_limit_mb=2048 -malloc_limit_mb=512 \
    -timeout=10 -max_len=65536 -print_final_stats=1 -artifact_prefix="$art/" >"$log" 2>&1
    echo "rc $?" >"$log.rc"; } 2>&1 | awk '{printf "%.0f", $1 + $2}')
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
