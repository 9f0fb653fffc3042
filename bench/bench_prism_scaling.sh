#!/usr/bin/env bash
# bench/bench_prism_scaling.sh: how the prism stage's cost grows with the
# wall (issue 22). The generated aircraft (vm-gen aircraft) at each
# resolution given, T = 5 % of its length, 20 layers, growth 1.2, one
# thread: per case the wall's triangles, the prisms, vm-prism's CPU and
# wall seconds (user + sys, /usr/bin/time), its peak memory and bytes per
# prism, the phases' seconds (thin, springback, cut, restore, march) and
# the marching's steps' (splits, stack smoothing, redistribution, first
# level, orthogonal solve, skewness relief, non-orthogonality relief), the
# phase at whose end the process's peak memory was reached, the share of
# columns at full thickness and the validity figures; then for each time
# and for the memory the exponent b of a least-squares fit cost ~ n^b over
# the cases, n the wall's triangles.
# usage: bench/bench_prism_scaling.sh BUILD_DIR [--res "4 8 16"] [--t 0.05]
#        [--layers 20] [--threads 1] [--keep DIR]
# (--keep DIR keeps each case's JSON and stderr there)
set -u
build=$(cd "$1" && pwd)
shift
res="4 8 16" t=0.05 layers=20 threads=1 keep=
while [ $# -gt 0 ]; do
  case $1 in
  --res) res=$2; shift 2 ;;
  --t) t=$2; shift 2 ;;
  --layers) layers=$2; shift 2 ;;
  --threads) threads=$2; shift 2 ;;
  --keep) keep=$2; shift 2 ;;
  *) echo "bench_prism_scaling.sh: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
bin=$build/apps
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
[ -n "$keep" ] && mkdir -p "$keep"
# one value of a JSON object's member: obj KEY FILE gives the {...} after
# "KEY": (flat objects only), val KEY TEXT the number after "KEY":
obj() { sed -n "s/.*\"$1\": {\([^}]*\)}.*/\1/p" "$2" | head -1; }
val() { echo "$2" | sed -n "s/.*\"$1\": \([^,}]*\).*/\1/p" | head -1; }
printf '| res. | triangles | prisms | CPU s | wall s | peak MB | B/prism | thin / springback / cut / restore / march s | marching: splits / stack / redistribution / first level / solve / skewness / non-orth. / growth s | peak reached in | full T | inverted, crossing, split negative |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|\n'
fit=$dir/fit.txt
: >"$fit"
for r in $res; do
  c=$dir/ac$r
  "$bin/vm-gen" aircraft --resolution "$r" "$c.vmsh" 2>"$c.gen" || {
    printf '| %s | vm-gen failed: %s |\n' "$r" "$(tail -1 "$c.gen")"
    continue
  }
  /usr/bin/time -f '%U %S %e %M' -o "$c.time" "$bin/vm-prism" -q --json --threads "$threads" \
    -t "$t" -n "$layers" "$c.vmsh" "$c.out.vmsh" >"$c.json" 2>"$c.err"
  rc=$?
  [ -n "$keep" ] && cp "$c.json" "$keep/ac$r.json" && cp "$c.err" "$keep/ac$r.err"
  rm -f "$c.out.vmsh"
  if [ ! -s "$c.json" ]; then
    printf '| %s | | | vm-prism failed (exit %s): %s |\n' "$r" "$rc" "$(tail -1 "$c.err")"
    continue
  fi
  read -r u s e m <"$c.time"
  j=$(cat "$c.json")
  cpu=$(echo "$u + $s" | bc -l)
  mb=$(echo "$m / 1024" | bc -l)
  np=$(val prisms "$j")
  tri=$(val wall_triangles "$j")
  tm=$(obj time "$c.json")
  mt=$(obj march_time "$c.json")
  pk=$(obj peak_mb "$c.json")
  phases="thin springback cut restore march"
  steps="splits stack_smoothing redistribution orthogonal_first_level orthogonal_solve skewness_relief nonortho_relief growth_relief"
  ph=$(for k in $phases; do val "$k" "{$tm}"; done | awk '{printf "%s%.1f", (NR > 1 ? " / " : ""), $1}')
  ms=$(for k in $steps; do val "$k" "{$mt}"; done | awk '{printf "%s%.1f", (NR > 1 ? " / " : ""), $1}')
  # the phase whose end first showed the peak (within 1 MB), else the
  # result, its check and the writing after the phases
  run=$(val run "{$pk}")
  where=$(for k in $phases; do echo "$k $(val "$k" "{$pk}")"; done |
    awk -v run="$run" '!f && $2 >= run - 1 {print $1; f = 1} END {if (!f) print "result and writing"}')
  printf '| %s | %s | %s | %.1f | %.1f | %.0f | %.0f | %s | %s | %s | %.1f %% | %s, %s, %s |\n' \
    "$r" "$tri" "$np" "$cpu" "$e" "$mb" "$(echo "$m * 1024 / $np" | bc -l)" "$ph" "$ms" "$where" \
    "$(echo "$(val full_fraction "$j") * 100" | bc -l)" "$(val inverted_corner_tets "$j")" \
    "$(val intersecting_pairs "$j")" "$(val split_negative "$j")"
  echo "$tri $cpu $mb $(for k in $phases; do val "$k" "{$tm}"; done | tr '\n' ' ')$(for k in $steps; do val "$k" "{$mt}"; done | tr '\n' ' ')" >>"$fit"
done
[ "$(wc -l <"$fit")" -ge 2 ] || exit 0
echo
echo "Fitted exponent b of cost ~ n^b (n: wall triangles; least squares on the logarithms; a figure under 0.05 s in some case is left out):"
echo
awk 'BEGIN {
  split("CPU peak_memory thin springback cut restore march splits stack_smoothing redistribution orthogonal_first_level orthogonal_solve skewness_relief nonortho_relief growth_relief", name, " ")
}
{ for (k = 2; k <= NF; k++) { x[NR] = log($1); y[NR, k] = $k } n = NR; nf = NF }
END {
  printf "| cost |"; for (k = 2; k <= nf; k++) printf " %s |", name[k - 1]; printf "\n|---|"
  for (k = 2; k <= nf; k++) printf "---|"; printf "\n| b |"
  for (k = 2; k <= nf; k++) {
    sx = sy = sxx = sxy = 0; m = 0; ok = 1
    for (i = 1; i <= n; i++) {
      if (y[i, k] < 0.05) { ok = 0; break }
      v = log(y[i, k]); sx += x[i]; sy += v; sxx += x[i] * x[i]; sxy += x[i] * v; m++
    }
    d = m * sxx - sx * sx
    if (ok && m >= 2 && d > 0) printf " %.2f |", (m * sxy - sx * sy) / d
    else printf " — |"
  }
  printf "\n"
}' "$fit"
