#!/bin/sh
# swf-view live during the demo: swf-sil (demo.cfg at its real rate, as a flight publishes: in
# lockstep a loaded machine can starve the view's receiver; 20 frames, recording so that the
# stereo frames go out on SWF_STEREO too) and swf-view as separate processes over LCM UDP
# multicast in a private network namespace whose only interface is loopback (RECIPES.md). The
# page is opened in headless Chromium BEFORE the flight starts and must, by itself, come to show
# the 20 navigation outputs, a navigation status, a non-empty hazard map, the image and its
# tracked features; the
# screenshot is kept (argument 5). Then swf-view is stopped and its counters checked: nothing
# malformed or lost, every output received.
# usage: view_demo_test.sh SWF-SIL SWF-VIEW CONFIG PAGE_CHECK SCREENSHOT_OUT
set -eu
sil=$1 view=$2 cfg=$3 check=$4 shot=$5
fail() { echo "FAIL: $*" >&2; exit 1; }
if [ "$(id -u)" -eq 0 ]; then ns="unshare -n"; else ns="unshare -rn"; fi
$ns true 2>/dev/null || fail "cannot create a network namespace (root or unprivileged user namespaces)"
command -v chromium >/dev/null || fail "chromium is not installed (tools/run installs it)"
dir=$(mktemp -d)
trap '[ -n "${KEEP:-}" ] || rm -rf "$dir"' EXIT
frames=20
$ns sh -c '
  set -e
  ip link set lo up
  ip route add 239.0.0.0/8 dev lo
  "$2" --port 0 --url-file "$5/url" > "$5/view.json" 2> "$5/view.err" &
  v=$!
  for i in $(seq 50); do [ -s "$5/url" ] && break; sleep 0.1; done
  url=$(cat "$5/url")
  /usr/bin/python3 "$4" "$url" --frames "$7" --image --features --screenshot "$6" --timeout 150 \
    > "$5/page.json" 2> "$5/page.err" &
  c=$!
  "$1" --config "$3" --set "pacing: realtime" --set "rt.mlockall: false" --set "rt.priority: 0" \
       --set "sim.frames: $7" --set "lcm.publish: true" --set "record.path: $5/descent.lcmlog" \
       --set "summary.path: $5/summary.json" 2> "$5/sil.err" || echo "swf-sil exit $?" >&2
  rc=0; wait $c || rc=$?
  kill -TERM $v; wait $v
  exit $rc
' sh "$sil" "$view" "$cfg" "$check" "$dir" "$shot" "$frames" || {
  cat "$dir/page.err" "$dir/view.err" "$dir/sil.err" >&2; fail "the page did not show the descent"; }
echo "page: $(cat "$dir/page.json")"
echo "swf-view: $(cat "$dir/view.json")"
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
[ "$(json "$dir/view.json" "d['frames']")" -eq $frames ] || fail "swf-view did not receive every nav_state_t"
[ "$(json "$dir/view.json" "d['bus']['malformed_total'] + d['bus']['lost_total']")" -eq 0 ] || fail "messages malformed or lost"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_HAZARD']['received']")" -ge 1 ] || fail "no hazard map"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_STEREO']['received']")" -eq $frames ] || fail "not every image"
[ "$(json "$dir/view.json" "d['bus']['channels']['SIM_TRUTH']['received']")" -eq $frames ] || fail "truth missing"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_FEATURES']['received']")" -eq $frames ] || fail "feature sets missing"
[ "$(json "$dir/page.json" "d['hazard_known_pixels']")" -gt 1000 ] || fail "hazard map (nearly) empty on the page"
[ -s "$shot" ] || fail "no screenshot"
echo PASS
