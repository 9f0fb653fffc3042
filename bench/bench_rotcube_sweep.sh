#!/usr/bin/env bash
# bench/bench_rotcube_sweep.sh: vm-volume with defaults on the rotated-cube
# family beyond Table 1 (issue 23, item 5): rotation axes z, (1,1,1),
# (0,1,1) and (1,2,3), angles k pi/8 (k = 1..8), inner half-sizes 0.25, 0.3,
# 0.35 and 0.4, for each n given. Per case: the exit code (0 certified
# valid, 3 not valid, impossible or stopped as stalled, 4 time limit), the time to a certified
# mesh, phi_min, min scaled Jacobian, cells not certified, the face pyramids
# OpenFOAM's checkMesh would call wrong, CPU seconds; then a summary per n. One thread, so that two sweeps can run side by side.
# usage: bench/bench_rotcube_sweep.sh BUILD_DIR [N ...]   (default N: 12)
#        VM_SWEEP_LIMIT=S  seconds per case (default 120, the issue's target)
#        VM_SWEEP_AXES="0,0,1 1,1,1" VM_SWEEP_ANGLES="pi/2 pi"
#        VM_SWEEP_INNER="0.3"      restrict the sweep
set -u
build=$(cd "$1" && pwd)
shift
sizes=${*:-12}
bin=$build/apps
limit=${VM_SWEEP_LIMIT:-120}
axes=${VM_SWEEP_AXES:-0,0,1 1,1,1 0,1,1 1,2,3}
angles=${VM_SWEEP_ANGLES:-pi/8 pi/4 3pi/8 pi/2 5pi/8 3pi/4 7pi/8 pi}
inners=${VM_SWEEP_INNER:-0.25 0.3 0.35 0.4}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }
printf '| n | axis | angle | inner | exit | certified after s | CPU s | phi_min | min SJ | not certified | wrong face pyramids | note |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for n in $sizes; do
  ok=0 bad=0 imp=0 slow=0 stalled=0 total=0 cpu_sum=0 worst_cpu=0 foam_bad=0
  for ax in $axes; do
    for an in $angles; do
      for in in $inners; do
        total=$((total + 1))
        c=$dir/c
        "$bin/vm-gen" rotcube --n "$n" --angle "$an" --axis "$ax" --inner "$in" "$c.vmsh" 2>/dev/null
        /usr/bin/time -f '%U %S' -o "$c.time" "$bin/vm-volume" --threads 1 --time-limit "$limit" \
          --json "$c.vmsh" "$c.out.vmsh" >"$c.json" 2>"$c.err"
        rc=$?
        cpu=$(tail -1 "$c.time" | awk '{ printf "%.1f", $1 + $2 }')
        note=""
        if grep -q "lies outside the" "$c.err"; then
          note="impossible: fixed vertices outside the boundary"
          imp=$((imp + 1))
        elif grep -q "all its vertices are fixed" "$c.err"; then
          note="impossible: an inverted cell of fixed vertices"
          imp=$((imp + 1))
        elif [ $rc -eq 0 ]; then
          ok=$((ok + 1))
          cpu_sum=$(awk -v a="$cpu_sum" -v b="$cpu" 'BEGIN { print a + b }')
          worst_cpu=$(awk -v a="$worst_cpu" -v b="$cpu" 'BEGIN { print (b > a ? b : a) }')
        elif [ $rc -eq 4 ]; then
          slow=$((slow + 1))
          note="time limit"
        elif grep -q '"stalled": true' "$c.json"; then
          stalled=$((stalled + 1))
          note="stalled (stopped, exit 3)"
        else
          bad=$((bad + 1))
          note=$(grep -m1 "error:" "$c.err" | cut -c1-80)
        fi
        tc=$(json "$c.json" time_certified)
        ci=$(json "$c.json" certified_invalid)
        cu=$(json "$c.json" certified_undecided)
        ncert=$([ -n "$ci" ] && echo $((ci + cu)))
        pyr=$(json "$c.json" foam_pyramid_errors)
        [ $rc -eq 0 ] && [ "${pyr:-0}" != 0 ] && foam_bad=$((foam_bad + 1))
        g3() { [ -n "$1" ] && awk -v x="$1" 'BEGIN { printf "%.3g", x }'; }
        [ "${tc:-}" = "-1.000" ] && tc=""
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$n" "$ax" "$an" "$in" \
          "$rc" "${tc:--}" "$cpu" "$(g3 "$(json "$c.json" phi_min)")" "$(g3 "$(json "$c.json" sj_min)")" \
          "${ncert:--}" "${pyr:--}" "$note"
      done
    done
  done
  printf '\nn = %s: %s cases: %s certified valid (CPU mean %s s, max %s s; %s of them with face pyramids OpenFOAM calls wrong), %s impossible (said at once), %s stopped as stalled, %s at the %s s limit, %s other exit 3\n\n' \
    "$n" "$total" "$ok" "$(awk -v s="$cpu_sum" -v k="$ok" 'BEGIN { printf "%.1f", k ? s / k : 0 }')" \
    "$worst_cpu" "$foam_bad" "$imp" "$stalled" "$slow" "$limit" "$bad"
done
