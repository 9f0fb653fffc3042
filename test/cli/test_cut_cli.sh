#!/usr/bin/env bash
# test/cli/test_cut_cli.sh: vm-convert --cut, a half model from a closed
# surface. plane.stl cut at y = 0: 9,343 triangles on the + side and 9,211
# on the - side, 549 border edges each (the issue's own cut: 9,343 and
# 549), every border vertex at y == 0 exactly (the text format prints
# 17 digits: "0"), no vertex on the wrong side, the two halves' volumes
# (each closed by the plane) adding up to the whole's within 1e-12; two
# runs give the same bytes. Bad planes exit 2 and an empty side exits 1,
# writing nothing.
set -u
conv=$1
plane="$VM_SOURCE_ROOT/../shared/data/plane.stl"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
[ -f "$plane" ] || { echo "skip: no $plane"; exit 77; }

# triangles, border edges, border vertices off y = 0, vertices on the
# wrong side (sign S), and the volume between the surface and y = 0
stats() {
  awk -v S="$2" '
    /^vertices /{nv=$2; mode="v"; i=0; next}
    /^elements /{mode="e"; nt=0; next}
    /^fields /{mode=""}
    mode=="v" && i<nv {x[i]=$1; y[i]=$2; z[i]=$3; ys[i]=$2; i++; next}
    mode=="e" && $1=="tri" {
      a=$2; b=$3; c=$4; nt++
      k[a<b?a" "b:b" "a]++; k[b<c?b" "c:c" "b]++; k[c<a?c" "a:a" "c]++
      # (y - 0) n_y over the triangle: the divergence theorem, field y e_y
      ny=(z[b]-z[a])*(x[c]-x[a])-(x[b]-x[a])*(z[c]-z[a])
      vol+=(y[a]+y[b]+y[c])/3*ny/2
    }
    END {
      nb=0; off=0; wrong=0
      for (e in k) if (k[e]==1) { nb++; split(e, p, " "); if (ys[p[1]]!="0" || ys[p[2]]!="0") off++ }
      for (v=0; v<nv; v++) if (S*y[v]<0) wrong++
      printf "%d %d %d %d %.17g\n", nt, nb, off, wrong, vol
    }' "$1"
}

"$conv" --cut y=0 "$plane" "$dir/p.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "cut at y=0, the + side kept: 17456 -> 9343 triangles.* 549 border edges$" "$dir/err"' \
  "plane.stl --cut y=0: the + side (the larger by a hair), said: $(cat "$dir/err")"
"$conv" -q --cut y=0:- "$plane" "$dir/m.vmsh" && "$conv" -q --cut y=0:+ "$plane" "$dir/p2.vmsh"
check '[ $? -eq 0 ] && cmp -s "$dir/p.vmsh" "$dir/p2.vmsh"' "y=0:+ is the default here, and two runs give the same bytes"
"$conv" -q "$dir/p.vmsh" "$dir/p.vmsht" && "$conv" -q "$dir/m.vmsh" "$dir/m.vmsht" &&
  "$conv" -q "$plane" "$dir/full.vmsht"
read -r pt pb poff pw pv <<<"$(stats "$dir/p.vmsht" 1)"
read -r mt mb moff mw mv <<<"$(stats "$dir/m.vmsht" -1)"
read -r ft fb foff fw fv <<<"$(stats "$dir/full.vmsht" 0)"
check '[ "$pt" = 9343 ] && [ "$pb" = 549 ] && [ "$poff" = 0 ] && [ "$pw" = 0 ]' \
  "+ half: $pt triangles, $pb border edges, $poff of them off y = 0, $pw vertices below"
check '[ "$mt" = 9211 ] && [ "$mb" = 549 ] && [ "$moff" = 0 ] && [ "$mw" = 0 ]' \
  "- half: $mt triangles, $mb border edges, $moff of them off y = 0, $mw vertices above"
check '[ "$fb" = 0 ] && awk -v a="$pv" -v b="$mv" -v f="$fv" "BEGIN{d=a+b-f; exit !(a>0 && b>0 && (d<0?-d:d)<=1e-12*f)}"' \
  "the halves' volumes $pv + $mv = the whole's $fv"

# bad planes: usage errors; an empty side: exit 1; nothing written
for p in "q=0" "y" "y=0:x" "y=abc"; do
  "$conv" --cut "$p" "$plane" "$dir/bad.stl" 2>"$dir/err"
  rc=$?
  check '[ $rc -eq 2 ] && [ ! -e "$dir/bad.stl" ] && [ "$(wc -l <"$dir/err")" -eq 1 ]' "--cut $p: exit 2, one line: $(cat "$dir/err")"
done
"$conv" --cut z=50:+ "$plane" "$dir/bad.stl" 2>"$dir/err"
rc=$?
check '[ $rc -eq 1 ] && [ ! -e "$dir/bad.stl" ] && grep -q "nothing of the model lies on the + side of z=50" "$dir/err"' \
  "--cut z=50:+: exit 1, nothing written: $(cat "$dir/err")"
exit $fail
