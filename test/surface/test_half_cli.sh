#!/usr/bin/env bash
# test/surface/test_half_cli.sh: half models through vm-surface (#20).
# plane.stl cut at y = 0 by vm-convert --cut, then vm-surface with its
# defaults: the plane y = 0 found and said, exit 0, every border vertex of
# the result at y == 0 bit for bit (the text format prints 17 digits:
# "0"), none below the plane, the attribute symmetry_plane "y=0" in the
# output; --symmetry y=0 gives the same bytes; the cut with --cut-snap 0.2
# (no needle beside the cut) gives a smallest angle above 5 degrees and at
# most 2 wall edges beyond 70 degrees (the full model's run beside it,
# for the log). Refused, exit 1, one line, nothing written: --symmetry
# y=0.5 (the border is not in it: the farthest vertex), --symmetry z=0 on
# a closed sphere, a border in two planes (plane.stl cut at y = 0 and
# z = 1), --wrap; --symmetry q=0: exit 2.
set -u
conv=$1 surf=$2 gen=$3
plane="$VM_SOURCE_ROOT/../shared/data/plane.stl"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
[ -f "$plane" ] || { echo "skip: no $plane"; exit 77; }
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }

# border vertices off y = 0, vertices below it, border vertices
border() {
  awk '
    /^vertices /{nv=$2; mode="v"; i=0; next}
    /^elements /{mode="e"; next}
    /^fields /{mode=""}
    mode=="v" && i<nv {ys[i]=$2; i++; next}
    mode=="e" && $1=="tri" {
      a=$2; b=$3; c=$4
      k[a<b?a" "b:b" "a]++; k[b<c?b" "c:c" "b]++; k[c<a?c" "a:a" "c]++
    }
    END {
      off=0; below=0; nb=0
      for (e in k) if (k[e]==1) { split(e, p, " "); bv[p[1]]=1; bv[p[2]]=1 }
      for (v in bv) { nb++; if (ys[v]!="0") off++ }
      for (v=0; v<nv; v++) if (ys[v]+0<0) below++
      printf "%d %d %d\n", off, below, nb
    }' "$1"
}

"$conv" -q --cut y=0 "$plane" "$dir/half.vmsh"
"$surf" --json "$dir/half.vmsh" "$dir/hs.vmsh" >"$dir/hs.json" 2>"$dir/hs.err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "symmetry plane y=0 (found: every border vertex lies in it): a half model, 549 border edges in 1 loops" "$dir/hs.err" && grep -q "\"symmetry\": {\"plane\": \"y=0\", \"axis\": \"y\", \"value\": 0, \"given\": false, \"side\": 1, \"border_edges_in\": 549" "$dir/hs.json"' \
  "the half of plane.stl: y=0 found and said (exit $rc)"
"$conv" -q "$dir/hs.vmsh" "$dir/hs.vmsht"
read -r off below nb <<<"$(border "$dir/hs.vmsht")"
check '[ "$off" = 0 ] && [ "$below" = 0 ] && [ "$nb" -gt 100 ] && [ "$nb" = "$(json "$dir/hs.json" border_vertices)" ] && [ "$(json "$dir/hs.json" off_plane)" = 0 ]' \
  "its result: $nb border vertices, $off off y == 0, $below vertices below the plane"
check 'grep -q "^\"symmetry_plane\" \"y=0\"$" "$dir/hs.vmsht"' "the output carries the attribute symmetry_plane y=0"
"$surf" -q --symmetry y=0 "$dir/half.vmsh" "$dir/hs2.vmsh"
check '[ $? -eq 0 ] && cmp -s "$dir/hs.vmsh" "$dir/hs2.vmsh"' "--symmetry y=0: the same bytes"

# the cut without needles beside it, and the full model beside it
"$conv" -q --cut y=0 --cut-snap 0.2 "$plane" "$dir/halfs.vmsh"
"$surf" --json "$dir/halfs.vmsh" "$dir/hss.vmsh" >"$dir/hss.json" 2>/dev/null
rc=$?
"$surf" --json "$plane" "$dir/full.vmsh" >"$dir/full.json" 2>/dev/null
"$conv" -q "$dir/hss.vmsh" "$dir/hss.vmsht"
read -r off below nb <<<"$(border "$dir/hss.vmsht")"
amin=$(json "$dir/hss.json" min_angle) o70=$(json "$dir/hss.json" over70_after)
check '[ $rc -eq 0 ] && [ "$off" = 0 ] && [ "$below" = 0 ] && awk -v a="$amin" -v o="$o70" "BEGIN{exit !(a>5 && o<=2)}"' \
  "--cut-snap 0.2 half: $(json "$dir/hss.json" faces) triangles, smallest angle $amin, $o70 edges beyond 70 deg, $nb border vertices all at y == 0; the full model: $(json "$dir/full.json" faces) triangles, smallest angle $(json "$dir/full.json" min_angle), $(json "$dir/full.json" over70_after) beyond 70"

bad() { # file, expected message, what, options...
  local f=$1 msg=$2 what=$3
  shift 3
  "$surf" -q "$@" "$f" "$dir/bad.vmsh" 2>"$dir/err"
  local rc=$?
  check '[ $rc -eq 1 ] && [ ! -e "$dir/bad.vmsh" ] && [ "$(wc -l <"$dir/err")" -eq 1 ] && grep -q "$msg" "$dir/err"' \
    "$what: exit $rc, one line: $(cat "$dir/err")"
}
bad "$dir/half.vmsh" "the border is not in the symmetry plane y=0.5 (given): 549 of its 549 border vertices are farther than .* the farthest (.*) by 0.5$" \
  "--symmetry y=0.5" --symmetry y=0.5
"$gen" sphere "$dir/sphere.stl"
bad "$dir/sphere.stl" "the symmetry plane z=0 is given, but the surface is closed" "--symmetry z=0 on a sphere" --symmetry z=0
"$conv" -q --cut z=1 "$dir/half.vmsh" "$dir/quarter.vmsh" 2>/dev/null
bad "$dir/quarter.vmsh" "open surface: .*; not a half model either: its border is in no plane x, y or z = C" \
  "a border in y = 0 and z = 1"
bad "$dir/half.vmsh" "a half model (symmetry plane y=0) is not wrapped" "--wrap 0.01" --wrap 0.01
"$surf" -q --symmetry q=0 "$dir/half.vmsh" "$dir/bad.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 2 ] && [ ! -e "$dir/bad.vmsh" ]' "--symmetry q=0: exit $rc: $(cat "$dir/err")"
exit $fail
