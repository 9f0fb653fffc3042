#!/usr/bin/env bash
# test/cli/test_prism_honest.sh: vm-prism refuses a self-intersecting wall
# it cannot repair at once, and says plainly when a run did not finish (issue 21, items 10
# and 13): a sphere poked through itself ran 72 s and exited 3, two
# overlapping spheres past 120 s (now exit 1 in well under a second, with
# the count of intersecting pairs and a location; the two spheres since
# session 42 only with --keep-wall: by default the surface stage unites
# them and the layer is built); --time-limit exited 0
# with "valid": true and 1 of 20 layers (now exit 4, "timed_out": true, the
# layers reached on stderr); a stopped run whose outer faces cross says
# NOT VALID; -T 1e-300 is a usage error, not bad input (item 14); a
# wall folded flat onto itself (a flap) gets its layer after the fold is
# taken out (refused before: no column direction there).
# usage: test_prism_honest.sh VM_GEN VM_CONVERT VM_PRISM
set -u
gen=$1 conv=$2 prism=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$gen" sphere --level 3 "$dir/s.vmsh" && "$conv" "$dir/s.vmsh" "$dir/s.off" || exit 1
# two IN.off DX OUT.off: IN and a copy shifted by DX along x, one OFF
two() {
  awk -v dx="$2" 'NR == 1 { next } NR == 2 { nv = $1; nf = $2; next }
    NR <= 2 + nv { v[NR - 3] = $0; next } { f[NR - 3 - nv] = $0 }
    END {
      print "OFF"; print 2 * nv, 2 * nf, 0
      for (i = 0; i < nv; i++) print v[i]
      for (i = 0; i < nv; i++) { split(v[i], a, " "); printf "%.17g %s %s\n", a[1] + dx, a[2], a[3] }
      for (i = 0; i < nf; i++) print f[i]
      for (i = 0; i < nf; i++) { split(f[i], a, " "); print 3, a[2] + nv, a[3] + nv, a[4] + nv }
    }' "$1" >"$3"
}
# the north pole pushed through the south side
awk 'NR == 2 { nv = $1 } NR > 2 && NR <= 2 + nv && $3 > 0.999 { $3 = -1.5 } { print }' \
  "$dir/s.off" >"$dir/poked.off"
two "$dir/s.off" 1.0 "$dir/overlap.off"
two "$dir/s.off" 2.02 "$dir/close.off" # 0.02 apart: the thin layer crosses
# two parts crossing each other are refused at once with --keep-wall (by
# default the surface stage unites them, below); a part pushed through
# itself goes to the surface stage, whose repair would heal a local fold
# but refuses to cut a spike off: at once, with how far and where
for f in poked overlap; do
  t0=$(date +%s%N)
  keep=()
  [ $f = overlap ] && keep=(--keep-wall)
  "$prism" -q "${keep[@]}" "$dir/$f.off" "$dir/o.vmsh" 2>"$dir/err"
  rc=$?
  ms=$((($(date +%s%N) - t0) / 1000000))
  if [ $f = overlap ]; then
    check '[ $rc -eq 1 ] && [ ! -e "$dir/o.vmsh" ] && grep -Eq "intersects itself: [0-9]+ pairs of triangles intersect, e.g. elements [0-9]+ and [0-9]+ near \(" "$dir/err" && [ $(wc -l <"$dir/err") -eq 1 ]' "$f sphere: refused as bad input, pairs and a location (exit $rc, $(cat "$dir/err"))"
  else
    check '[ $rc -eq 1 ] && [ ! -e "$dir/o.vmsh" ] && tail -1 "$dir/err" | grep -Eq "error: .*the surface stage: self-intersecting surface: [0-9]+ pairs of faces intersect, [0-9]+ of them within one closed component, which intersects itself near \(.*\): healing would move the surface by more than twice the local edge length \(moved 0\.8[0-9]*, local edge length 0\.1[0-9]*\)"' "$f sphere: refused as bad input, how far and where (exit $rc, $(cat "$dir/err"))"
  fi
  check '[ $ms -lt 5000 ]' "$f sphere: refused in ${ms} ms"
done
# the north pole moved two edge lengths sideways along the sphere: its
# fan folds over its neighbours (a model's local fold), which the surface
# stage heals; the layer is built on the healed wall
awk 'NR == 2 { nv = $1 } NR > 2 && NR <= 2 + nv && $3 > 0.999 { $1 = 0.30146 / 1.04441; $3 = 1 / 1.04441 } { print }' \
  "$dir/s.off" >"$dir/fold.off"
"$prism" -q --json "$dir/fold.off" "$dir/o.vmsh" >"$dir/j" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/j" && grep -q "\"surface_stage\": true" "$dir/j" && grep -Eq "repair: 1 closed components intersected themselves \([0-9]+ pairs of faces\): their crossing faces removed and the holes filled" "$dir/err"' \
  "folded sphere: healed by the surface stage, a valid layer (exit $rc, $(head -c 400 "$dir/err"))"
rm -f "$dir/o.vmsh"
# a flap: one triangle split by a point pushed 0.3 of its height past an
# edge, in its plane, lifted by 1e-5 (no two triangles intersect): the
# wall folds back there (main refused it: no column direction), and the
# folds are taken out before the layer
awk 'NR == 1 { next } NR == 2 { nv = $1; nf = $2; next }
  NR <= 2 + nv { v[NR - 3] = $0; next } { f[NR - 3 - nv] = $0 }
  END {
    split(f[0], t, " "); a = t[2]; b = t[3]; c = t[4]
    split(v[a], A, " "); split(v[b], B, " "); split(v[c], C, " ")
    for (r = 1; r <= 3; r++) { u[r] = B[r] - A[r]; w[r] = C[r] - A[r] }
    n[1] = u[2] * w[3] - u[3] * w[2]; n[2] = u[3] * w[1] - u[1] * w[3]; n[3] = u[1] * w[2] - u[2] * w[1]
    l = sqrt(n[1] ^ 2 + n[2] ^ 2 + n[3] ^ 2)
    for (r = 1; r <= 3; r++) { m = (A[r] + B[r]) / 2; p[r] = m + 0.3 * (m - C[r]) + 1e-5 * n[r] / l }
    print "OFF"; print nv + 1, nf + 2, 0
    for (i = 0; i < nv; i++) print v[i]
    printf "%.17g %.17g %.17g\n", p[1], p[2], p[3]
    print 3, a, b, nv; print 3, b, c, nv; print 3, c, a, nv
    for (i = 1; i < nf; i++) print f[i]
  }' "$dir/s.off" >"$dir/flap.off"
"$prism" -q --json "$dir/flap.off" "$dir/o.vmsh" >"$dir/j" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/j" && grep -Eq "\"folded_in\": [1-9][0-9]*, \"folded\": 0" "$dir/j" && grep -Eq "the wall folds back at [0-9]+ vertices .*took [0-9]+ of them out" "$dir/err"' \
  "flap sphere: the fold taken out, a valid layer (exit $rc, $(head -c 400 "$dir/err"))"
rm -f "$dir/o.vmsh"
"$prism" -q --json "$dir/overlap.off" "$dir/o.vmsh" >"$dir/j" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && grep -q "\"valid\": true" "$dir/j" && grep -q "\"surface_stage\": true" "$dir/j" && grep -q "the wall intersects itself (246 pairs of triangles): overlapping closed parts are replaced by their union" "$dir/err"' \
  "overlap spheres: united by the surface stage, a valid layer (exit $rc, $(head -c 300 "$dir/err"))"
"$prism" -q --json --time-limit 1e-9 "$dir/s.off" "$dir/o.vmsh" >"$dir/j" 2>"$dir/err"
rc=$?
check '[ $rc -eq 4 ] && [ -s "$dir/o.vmsh" ]' "--time-limit: exit 4, the mesh so far written (exit $rc)"
check 'grep -q "\"timed_out\": true" "$dir/j" && grep -q "\"valid\": false" "$dir/j"' "--time-limit: \"timed_out\": true, \"valid\": false in --json"
check 'grep -Eq "stopped at the time limit after .*: 1 of 20 layers" "$dir/err"' "--time-limit: the layers reached said on stderr, even with -q ($(cat "$dir/err"))"
"$prism" -q --json --time-limit 1e-9 "$dir/close.off" "$dir/o2.vmsh" >"$dir/j" 2>"$dir/err"
rc=$?
check '[ $rc -eq 4 ] && grep -q "NOT VALID: .* [1-9][0-9]* pairs of outer/wall faces crossing" "$dir/err"' "a stopped run whose outer faces cross says NOT VALID (exit $rc: $(cat "$dir/err"))"
"$prism" -q -T 1e-300 "$dir/s.off" "$dir/o3.vmsh" 2>"$dir/err"
rc=$?
check '[ $rc -eq 2 ] && grep -q "thickness 1e-300 is below" "$dir/err" && [ ! -e "$dir/o3.vmsh" ]' "-T 1e-300: a usage error naming the thickness (exit $rc: $(cat "$dir/err"))"
exit $fail
