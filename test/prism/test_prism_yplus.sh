#!/usr/bin/env bash
# test/prism/test_prism_yplus.sh: the first layer from a target y+ (issue 24,
# item 5). --yplus Y --reynolds RE [--ref-length L] sets the first height to
# the flat-plate estimate h1 = Y L / (RE sqrt(Cf/2)), Cf = (2 log10 RE -
# 0.65)^-2.3 (Schlichting), L the model's length unless given; without
# --growth the ratio is solved so the layers fill the thickness (also for
# --first-height, which kept 1.2 and left the remainder to the last layer);
# bad combinations are usage errors.
# usage: test_prism_yplus.sh VM_PRISM VM_GEN
set -u
prism=$1 gen=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if eval "$1"; then echo "ok: $2"; else echo "FAIL: $2"; fail=1; fi; }
json() { sed -n "s/.*\"$2\": \([^,}]*\).*/\1/p" "$1" | head -1; }
"$gen" sphere --level 2 "$dir/s.vmsh" || exit 1
# the formula, independently (awk: log10 x = log(x)/log(10))
h1() { awk -v y="$1" -v re="$2" -v l="$3" 'BEGIN { cf = (2 * log(re) / log(10) - 0.65) ^ -2.3;
  printf "%.17g", y * l / (re * sqrt(cf / 2)) }'; }
close() { awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(d <= t * (b < 0 ? -b : b)) }'; }
# the schedule fills T: h1 (r^n - 1) / (r - 1)
fills() { awk -v h="$1" -v r="$2" -v n="$3" -v T="$4" 'BEGIN { s = (r == 1) ? h * n : h * (r ^ n - 1) / (r - 1);
  d = s - T; if (d < 0) d = -d; exit !(d <= 1e-6 * T) }'; }

"$prism" -q --json -n 10 -T 0.2 --yplus 1 --reynolds 1e6 --ref-length 1 "$dir/s.vmsh" "$dir/a.vmsh" >"$dir/a.json"
rc=$?
want=$(h1 1 1e6 1)
got=$(json "$dir/a.json" first_height)
check "[ $rc -eq 0 ] && close $got $want 1e-12" "y+ 1 at Re 1e6 over L = 1: first height $got, flat plate $want (exit $rc)"
r=$(json "$dir/a.json" growth)
check "fills $got $r 10 0.2 && [ \$(json $dir/a.json layers) -eq 10 ]" "the growth $r is solved: 10 layers fill T = 0.2"
check "awk -v v=$(json "$dir/a.json" valid) 'BEGIN { exit !(v == \"true\") }'" "the layer is valid"

# the reference length defaults to the model's (the unit sphere: 2)
"$prism" -q --json -n 10 -T 0.2 --yplus 5 --reynolds 3e5 "$dir/s.vmsh" "$dir/b.vmsh" >"$dir/b.json"
L=$(json "$dir/b.json" model_length)
want=$(h1 5 3e5 "$L")
got=$(json "$dir/b.json" first_height)
check "close $got $want 1e-12" "y+ 5 at Re 3e5 over the model's length $L: first height $got, flat plate $want"

# --first-height alone solves the growth too (it kept 1.2 before)
"$prism" -q --json -n 5 -T 0.2 --first-height 0.01 "$dir/s.vmsh" "$dir/c.vmsh" >"$dir/c.json"
r=$(json "$dir/c.json" growth)
check "fills 0.01 $r 5 0.2" "--first-height 0.01 alone: growth $r solved, 5 layers fill T"
# with --growth given, the growth law is kept
"$prism" -q --json -n 5 -T 0.2 --first-height 0.01 --growth 1.3 "$dir/s.vmsh" "$dir/d.vmsh" >"$dir/d.json"
check "[ \"$(json "$dir/d.json" growth)\" = 1.3 ]" "--first-height with --growth 1.3 keeps 1.3"

# usage errors: exit 2, one line, nothing written
for bad in "--yplus 1" "--reynolds 1e6" "--yplus 1 --reynolds 1e6 --first-height 0.01" \
  "--yplus 1 --reynolds 5" "--yplus -1 --reynolds 1e6" "--yplus 1 --reynolds 1e6 --ref-length 0"; do
  "$prism" -q $bad "$dir/s.vmsh" "$dir/e.vmsh" 2>"$dir/err"
  rc=$?
  check "[ $rc -eq 2 ] && [ \$(wc -l <$dir/err) -eq 1 ] && [ ! -e $dir/e.vmsh ]" "'$bad' is a usage error (exit $rc: $(cat "$dir/err"))"
done
exit $fail
