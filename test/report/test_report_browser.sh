#!/usr/bin/env bash
# test/report/test_report_browser.sh: the report page renders in a browser:
# a headless Chromium takes a screenshot of index.html of a vm-volume
# report; the screenshot must decode, show more than one colour and, as the
# window is tall enough to reach the first figure (the convergence plot),
# the plot's red curve of M (a page with broken images has no red).
# Exit 77 (skipped) when no Chromium is installed (Debian: chromium).
set -u
gen=$1 vol=$2 tr=$4
browser=
for b in chromium chromium-browser google-chrome; do
  if command -v "$b" >/dev/null 2>&1; then browser=$(command -v "$b"); break; fi
done
if [ -z "$browser" ]; then
  echo "skip: no chromium installed"
  exit 77
fi
"$tr" --png /dev/null >/dev/null 2>&1
if [ $? -eq 77 ]; then
  echo "skip: built without cairo"
  exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$gen" rotcube --n 8 --angle pi/2 "$dir/rc.vmsh" || exit 1
"$vol" -q --report "$dir/rep" "$dir/rc.vmsh" "$dir/out.vmsh" || exit 1
# no network, no GPU, no profile outside $dir; some builds ignore
# --screenshot=PATH unless run from a writable directory, so cd there
cd "$dir" || exit 1
timeout 240 "$browser" --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync \
  --disable-dev-shm-usage --user-data-dir="$dir/profile" --screenshot="$dir/shot.png" \
  --window-size=1200,1600 "file://$dir/rep/index.html" >"$dir/log" 2>&1
rc=$?
if [ ! -s "$dir/shot.png" ]; then
  echo "FAIL: no screenshot (chromium exit $rc)"
  tail -n 20 "$dir/log"
  exit 1
fi
"$tr" --png-red 300 "$dir/shot.png" ||
  { echo "FAIL: the screenshot is unreadable, blank or shows no figure"; exit 1; }
echo "ok: chromium rendered the report ($(stat -c %s "$dir/shot.png") bytes)"
