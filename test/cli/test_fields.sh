#!/usr/bin/env bash
# test/cli/test_fields.sh: the stages keep the user's fields (issue 21,
# item 5): vm-prism carries the wall's element fields up the columns (every
# prism, and its wall and outer face, takes its wall triangle's value) as
# it does vertex fields, and says which fields it does not carry;
# vm-surface's repair keeps fields through a repair that changes nothing
# and maps them through one that merges duplicate points.
# usage: test_fields.sh VM_GEN VM_PRISM VM_SURFACE
set -u
gen=$1 prism=$2 surf=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
"$gen" sphere --level 2 "$dir/s.vmsht" || exit 1
# with_fields IN OUT [soup]: IN's fields replaced by the vertex field
# "w" = x + 2y + 3z, the element fields "zone" (i32) = floor(10 x) of the
# triangle's centroid and "layer" (a name vm-prism writes itself); soup:
# every triangle on its own three copies of its vertices
with_fields() {
  awk -v soup="${3:-0}" '
    $1 == "vertices" { nv = $2; mode = "v"; k = 0; next }
    $1 == "elements" { ne = $2; mode = "e"; k = 0; next }
    $1 == "fields" { mode = "x"; next }
    mode == "v" && k < nv { x[k] = $1; y[k] = $2; z[k] = $3; k++; next }
    mode == "e" && k < ne { a[k] = $2; b[k] = $3; c[k] = $4; k++; next }
    END {
      printf "vmsht 1 0\ndim 3\n"
      if (soup) {
        printf "vertices %d\n", 3 * ne
        for (e = 0; e < ne; e++) {
          printf "%.17g %.17g %.17g free -1\n", x[a[e]], y[a[e]], z[a[e]]
          printf "%.17g %.17g %.17g free -1\n", x[b[e]], y[b[e]], z[b[e]]
          printf "%.17g %.17g %.17g free -1\n", x[c[e]], y[c[e]], z[c[e]]
        }
        printf "elements %d\n", ne
        for (e = 0; e < ne; e++) printf "tri %d %d %d\n", 3 * e, 3 * e + 1, 3 * e + 2
        printf "fields 3\nfield vertex f64 1 \"w\"\n"
        for (e = 0; e < ne; e++) {
          printf "%.17g\n", x[a[e]] + 2 * y[a[e]] + 3 * z[a[e]]
          printf "%.17g\n", x[b[e]] + 2 * y[b[e]] + 3 * z[b[e]]
          printf "%.17g\n", x[c[e]] + 2 * y[c[e]] + 3 * z[c[e]]
        }
      } else {
        printf "vertices %d\n", nv
        for (v = 0; v < nv; v++) printf "%.17g %.17g %.17g free -1\n", x[v], y[v], z[v]
        printf "elements %d\n", ne
        for (e = 0; e < ne; e++) printf "tri %d %d %d\n", a[e], b[e], c[e]
        printf "fields 3\nfield vertex f64 1 \"w\"\n"
        for (v = 0; v < nv; v++) printf "%.17g\n", x[v] + 2 * y[v] + 3 * z[v]
      }
      printf "field element i32 1 \"zone\"\n"
      for (e = 0; e < ne; e++) printf "%d\n", int(10 * (x[a[e]] + x[b[e]] + x[c[e]]) / 3 + 100)
      printf "field element i32 1 \"layer\"\n"
      for (e = 0; e < ne; e++) printf "7\n"
      printf "attributes 0\nend\n"
    }' "$1" >"$2"
}
# verify OUT NWALLTRI: every vertex's "w" matches its column's wall vertex
# (vm-prism) or its own coordinates (vm-surface, ncol 0); every element's
# "zone" matches its wall triangle (element e of a prism mesh stands on
# wall triangle e mod NWALLTRI, whose first three vertices are the wall's)
verify() {
  awk -v nt="$2" '
    $1 == "vertices" { nv = $2; mode = "v"; k = 0; next }
    $1 == "elements" { ne = $2; mode = "e"; k = 0; next }
    $1 == "field" { mode = $2 ":" $5; gsub(/"/, "", mode); k = 0; next }
    mode == "v" && k < nv { x[k] = $1; y[k] = $2; z[k] = $3; k++; next }
    mode == "e" && k < ne { a[k] = $2; b[k] = $3; c[k] = $4; k++; next }
    mode == "vertex:w" && k < nv { w[k++] = $1; hw = 1; next }
    mode == "element:zone" && k < ne { zn[k++] = $1; hz = 1; next }
    END {
      bad = 0
      if (!hw || !hz) { print "missing field: w " hw ", zone " hz; exit 1 }
      nw = nt ? nv / (ne / nt - 1) : nv   # vertices per level
      for (v = 0; v < nv; v++) {
        u = v % nw
        d = w[v] - (x[u] + 2 * y[u] + 3 * z[u])
        if (d > 1e-12 || d < -1e-12) { if (bad++ < 3) print "vertex " v ": w " w[v]; }
      }
      for (e = 0; e < ne; e++) {
        t = nt ? e % nt : e
        want = int(10 * (x[a[t]] + x[b[t]] + x[c[t]]) / 3 + 100)
        if (zn[e] != want) { if (bad++ < 3) print "element " e ": zone " zn[e] " not " want; }
      }
      exit bad > 0
    }' "$1"
}
with_fields "$dir/s.vmsht" "$dir/f.vmsht"
with_fields "$dir/s.vmsht" "$dir/soup.vmsht" 1
ntri=$(awk '$1 == "elements" { print $2 }' "$dir/s.vmsht")

"$prism" -n 3 "$dir/f.vmsht" "$dir/p.vmsht" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && verify "$dir/p.vmsht" $ntri' "vm-prism carries the wall's vertex and element fields up the columns (exit $rc)"
check 'grep -q "element field .layer. is not carried" "$dir/err"' "vm-prism says which wall field it does not carry"

"$surf" repair "$dir/f.vmsht" "$dir/r.vmsht" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && verify "$dir/r.vmsht" 0 && grep -q "\"layer\"" "$dir/r.vmsht"' "vm-surface repair that changes nothing keeps every field (exit $rc)"
check '! grep -q "dropped" "$dir/err"' "... and says nothing is dropped"

"$surf" repair "$dir/soup.vmsht" "$dir/r2.vmsht" 2>"$dir/err"
rc=$?
check '[ $rc -eq 0 ] && verify "$dir/r2.vmsht" 0' "vm-surface repair of a soup (points merged) maps the fields onto the merged mesh (exit $rc)"
check '[ $(awk "\$1 == \"vertices\" { print \$2 }" "$dir/r2.vmsht") -lt $((3 * ntri)) ]' "... which did merge points"
exit $fail
