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
export private_network_sh="$(cd "$(dirname "$0")/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
choose_private_network || fail "cannot create a network namespace (root or unprivileged user namespaces)"
command -v chromium >/dev/null || fail "chromium is not installed (tools/run installs it)"
make_scratch_dir
frames=20
$ns sh -c '
  set -e
  . "$private_network_sh"
  multicast_on_loopback
  start_view "$2" "$5"
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
[ "$(json "$dir/view.json" "d['frames']")" -eq $frames ] || fail "swf-view did not receive every nav_state_t"
[ "$(json "$dir/view.json" "d['bus']['malformed_total'] + d['bus']['lost_total']")" -eq 0 ] || fail "messages malformed or lost"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_HAZARD']['received']")" -ge 1 ] || fail "no hazard map"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_STEREO']['received']")" -eq $frames ] || fail "not every image"
[ "$(json "$dir/view.json" "d['bus']['channels']['SIM_TRUTH']['received']")" -eq $frames ] || fail "truth missing"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_FEATURES']['received']")" -eq $frames ] || fail "feature sets missing"
[ "$(json "$dir/page.json" "d['hazard_known_pixels']")" -gt 1000 ] || fail "hazard map (nearly) empty on the page"
[ -s "$shot" ] || fail "no screenshot"
echo PASS
