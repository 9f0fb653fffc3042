#!/usr/bin/env bash
# bench/bench_prism_peer.sh: the prism stage beside its peer, in the same
# run (issue 22). Per case (plane.stl and the generated aircraft, or the STL
# files given, 20 layers, T = 5 % and 20 % of the model's length):
# vm-prism's CPU seconds (user + sys), wall seconds, peak memory and bytes
# per prism, its phases' wall seconds (thin, springback, cut, restore,
# march) and validity (inverted corner tets, intersecting pairs); then
# Gmsh's boundary-layer extrusion of the same STL with the same layer
# heights (bench/peer_gmsh_extrude.py, Debian's python3-gmsh): its CPU and
# wall seconds, peak memory and prisms that are not positive; both sides'
# prisms not positive in every 3-tet split (a solver splitting prisms into
# tets fails there: vm-prism's count, then Gmsh's, corner failures
# included); and the ratio of CPU times.
# usage: bench/bench_prism_peer.sh BUILD_DIR [SHARED_DATA_DIR] [--threads N]
#        [--t "0.05 0.2"] [STL...]
# (threads: vm-prism's --threads, default 1 so CPU and wall compare alike)
set -u
build=$(cd "$1" && pwd)
shift
data=$(cd "$(dirname "$0")/../.." && pwd)/shared/data
if [ $# -gt 0 ] && [ -d "$1" ]; then
  data=$(cd "$1" && pwd)
  shift
fi
threads=1 ts="0.05 0.2" models=()
while [ $# -gt 0 ]; do
  case $1 in
  --threads) threads=$2; shift 2 ;;
  --t) ts=$2; shift 2 ;;
  *) models+=("$1"); shift ;;
  esac
done
bin=$build/apps
here=$(cd "$(dirname "$0")" && pwd)
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
if [ ${#models[@]} -eq 0 ]; then
  "$bin/vm-gen" aircraft "$dir/aircraft.stl" || exit 1
  models=("$data/plane.stl" "$dir/aircraft.stl")
fi
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }
len() { # the model's length: the largest extent of its bounding box
  "$bin/vm-prism" -q --json -n 1 -t 0.001 --time-limit 0.001 "$1" "$dir/len.vmsh" 2>/dev/null |
    sed -n 's/.*"model_length": \([^,}]*\).*/\1/p'
}
peer_ok=0
/usr/bin/python3 -c 'import gmsh, numpy' 2>/dev/null && peer_ok=1
printf '| case | tri | T/L | prisms | vm-prism CPU s | wall s | MB | B/prism | thin / springback / cut / restore / march s | inverted, crossing, split negative | Gmsh CPU s | wall s | MB | not positive | split negative | CPU ratio |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for model in "${models[@]}"; do
  name=$(basename "$model" .stl)
  L=$(len "$model")
  for t in $ts; do
    c=$dir/$name-$t
    /usr/bin/time -f '%U %S %e %M' -o "$c.time" "$bin/vm-prism" -q --json --threads "$threads" \
      -t "$t" -n 20 "$model" "$c.vmsh" >"$c.json" 2>"$c.err"
    rc=$?
    if [ ! -s "$c.json" ]; then
      printf '| %s | | %s | vm-prism failed (exit %s): %s |\n' "$name" "$t" "$rc" "$(tail -1 "$c.err")"
      continue
    fi
    read -r u s e m <"$c.time"
    cpu=$(echo "$u + $s" | bc -l)
    np=$(json "$c.json" prisms)
    tri=$(json "$c.json" wall_triangles)
    ph=$(sed -n 's/.*"time": {"thin": \([^,]*\), "springback": \([^,]*\), "cut": \([^,]*\), "restore": \([^,]*\), "march": \([^,]*\),.*/\1 \2 \3 \4 \5/p' "$c.json" |
      awk '{printf "%.1f / %.1f / %.1f / %.1f / %.1f", $1, $2, $3, $4, $5}')
    inv=$(json "$c.json" inverted_corner_tets)
    cross=$(json "$c.json" intersecting_pairs)
    split=$(json "$c.json" split_negative)
    peer="- | - | - | - | - | -"
    if [ $peer_ok = 1 ]; then
      T=$(echo "$t * $L" | bc -l)
      p=$(/usr/bin/python3 "$here/peer_gmsh_extrude.py" "$model" "$T" 20 2>/dev/null | tail -1)
      pc=$(echo "$p" | sed -n 's/.*"cpu_s": \([0-9.]*\).*/\1/p')
      pw=$(echo "$p" | sed -n 's/.*"wall_s": \([0-9.]*\).*/\1/p')
      pm=$(echo "$p" | sed -n 's/.*"peak_mib": \([0-9.]*\).*/\1/p')
      pb=$(echo "$p" | sed -n 's/.*"not_positive_prisms": \([0-9]*\).*/\1/p')
      pp=$(echo "$p" | sed -n 's/.*"prisms": \([0-9]*\).*/\1/p')
      ps=$(echo "$p" | sed -n 's/.*"split_negative_prisms": \([0-9]*\).*/\1/p')
      if [ -n "$pc" ]; then
        peer=$(printf '%s | %s | %.0f | %s of %s | %s | %.0f' "$pc" "$pw" "$pm" "$pb" "$pp" "$ps" \
          "$(echo "$cpu / ($pc + 0.01)" | bc -l)")
      else
        peer="Gmsh failed | | | | |"
      fi
    fi
    printf '| %s | %s | %s | %s | %.1f | %.1f | %.0f | %.0f | %s | %s, %s, %s | %s |\n' "$name" "$tri" "$t" "$np" \
      "$cpu" "$e" "$(echo "$m / 1024" | bc -l)" "$(echo "$m * 1024 / $np" | bc -l)" "$ph" "$inv" "$cross" "$split" "$peer"
  done
done
