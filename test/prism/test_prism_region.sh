#!/usr/bin/env bash
# test/prism/test_prism_region.sh: vm-prism --region-thickness FIELD:ID=X,...
# (issue 24, item 5) on vm-gen's aircraft with its 'component' field: the
# values in the unit of -t (a share of the model's length) or of -T, the
# thickest region's value as the run's thickness, each column's aim in the
# output's 'target_thickness' field (the least of its faces', graded), the
# wall's field carried up to the prisms, a value no face has is a warning,
# and malformed specifications are usage errors (exit 2, one line, nothing
# written). The aims' known answers are test_prism_region.c's.
# usage: test_prism_region.sh VM_PRISM VM_GEN VM_CONVERT
set -u
prism=$1 gen=$2 convert=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }
near() { awk -v a="$1" -v b="$2" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= 1e-12 * (b < 0 ? -b : b)) }'; }
# min, max and count at the min of the vertex field $2 of the legacy VTK file $1
field_stats() {
  awk -v f="$2" '$1 == f && NF == 4 { n = $3; on = 1; next }
    on { for (i = 1; i <= NF && n > 0; i++) { v = $i + 0; n--; vals[++m] = v;
           if (m == 1 || v < lo) lo = v; if (m == 1 || v > hi) hi = v }
         if (n == 0) on = 0 }
    END { c = 0; for (k = 1; k <= m; k++) c += vals[k] == lo; printf "%.17g %.17g %d\n", lo, hi, c }' "$1"
}
"$gen" aircraft --resolution 1 --components "$dir/a.vmsh" || exit 1

# the fuselage (component 0) at 2 % of the length, the rest at -t's 5 %
"$prism" -q --json -n 5 --region-thickness component:0=0.02 "$dir/a.vmsh" "$dir/r.vmsh" >"$dir/r.json"
rc=$?
L=$(json "$dir/r.json" model_length)
check "[ $rc -eq 0 ] && [ \"\$(json $dir/r.json valid)\" = true ]" "component:0=0.02: exit $rc, valid"
check "near \$(json $dir/r.json thickness) \$(awk -v l=$L 'BEGIN { printf \"%.17g\", 0.05 * l }')" \
  "the run's thickness is the thickest region's: $(json "$dir/r.json" thickness) (5 % of $L)"
"$convert" -q "$dir/r.vmsh" "$dir/r.vtk" 2>/dev/null
read -r lo hi nlo < <(field_stats "$dir/r.vtk" target_thickness)
check "near $lo \$(awk -v l=$L 'BEGIN { printf \"%.17g\", 0.02 * l }') && near $hi \$(awk -v l=$L 'BEGIN { printf \"%.17g\", 0.05 * l }')" \
  "aims from $lo (2 % of the length) to $hi (5 %)"
check "[ ${nlo:-0} -gt 1000 ]" "$nlo vertices (all levels) aim at the fuselage's value"
check "grep -q '^component 1 ' $dir/r.vtk" "the wall's component field is carried to the prisms"

# absolute with -T; a region thicker than -T sets the run's thickness
"$prism" -q --json -n 5 -T 0.4 --region-thickness component:1=0.6,2=0.6 "$dir/a.vmsh" "$dir/s.vmsh" >"$dir/s.json" 2>"$dir/s.err"
rc=$?
check "[ $rc -eq 0 ] && near \$(json $dir/s.json thickness) 0.6" "-T 0.4 with the wings at 0.6: exit $rc, thickness $(json "$dir/s.json" thickness)"
"$convert" -q "$dir/s.vmsh" "$dir/s.vtk" 2>/dev/null
read -r lo hi nlo < <(field_stats "$dir/s.vtk" target_thickness)
check "near $lo 0.4 && near $hi 0.6" "aims from $lo to $hi"

# a value no face has: a warning, the run goes on
"$prism" -q -n 2 --region-thickness component:9=0.01 "$dir/a.vmsh" "$dir/w.vmsh" 2>"$dir/w.err"
rc=$?
check "[ $rc -eq 0 ] && grep -q 'no wall face has component = 9' $dir/w.err" "component:9: exit $rc, $(head -1 "$dir/w.err")"

# usage errors: exit 2, one line, nothing written
for bad in "nosuch:0=0.1" "component" "component:" "component:0" "component:0=" "component:0=-1" \
  "component:x=0.1" "component:0=0.1," "component:0=0.1;1=0.2" "vm_flag:0=0.1" "component:0=1e-12"; do
  "$prism" -q --region-thickness "$bad" "$dir/a.vmsh" "$dir/e.vmsh" 2>"$dir/err"
  rc=$?
  check "[ $rc -eq 2 ] && [ \$(wc -l <$dir/err) -eq 1 ] && [ ! -e $dir/e.vmsh ]" "'$bad' is a usage error (exit $rc: $(cat "$dir/err"))"
done
exit $fail
