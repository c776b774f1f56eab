#!/bin/sh
# swf-view driven by swf-replay: a short demo descent (10 frames) is flown and recorded without
# publishing, then swf-replay re-runs the flight process on that log and publishes over LCM UDP
# multicast in a private network namespace. The page, opened before the replay starts, must come
# to show the 10 outputs, a status, tracked features, the image (a publishing replay sends the
# replayed frames on SWF_STEREO without recording them) and a non-empty hazard map.
# usage: view_replay_test.sh SWF-SIL SWF-REPLAY SWF-VIEW CONFIG PAGE_CHECK
set -eu
sil=$1 replay=$2 view=$3 cfg=$4 check=$5
export private_network_sh="$(cd "$(dirname "$0")/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
choose_private_network || fail "cannot create a network namespace (root or unprivileged user namespaces)"
make_scratch_dir
frames=10
"$sil" --config "$cfg" --set "pacing: lockstep" --set "rt.mlockall: false" --set "rt.priority: 0" \
  --set "sim.frames: $frames" --set "lcm.publish: false" --set "record.path: $dir/flown.lcmlog" \
  --set "summary.path: $dir/flown.json" 2> "$dir/sil.err" || { cat "$dir/sil.err" >&2; fail "swf-sil"; }
$ns sh -c '
  set -e
  . "$private_network_sh"
  multicast_on_loopback
  start_view "$2" "$5"
  /usr/bin/python3 "$4" "$url" --frames "$6" --features --image --screenshot "$5/replay.png" \
    --timeout 150 > "$5/page.json" 2> "$5/page.err" &
  c=$!
  "$1" --config "$3" --log "$5/flown.lcmlog" \
       --set "pacing: lockstep" --set "rt.mlockall: false" --set "rt.priority: 0" \
       --set "lcm.publish: true" --set "summary.path: $5/replayed.json" \
       --record "$5/replayed.lcmlog" 2> "$5/replay.err" \
    || echo "swf-replay exit $?" >&2
  rc=0; wait $c || rc=$?
  kill -TERM $v; wait $v
  exit $rc
' sh "$replay" "$view" "$cfg" "$check" "$dir" "$frames" || {
  cat "$dir/page.err" "$dir/view.err" "$dir/replay.err" >&2; fail "the page did not show the replay"; }
echo "page: $(cat "$dir/page.json")"
echo "swf-view: $(cat "$dir/view.json")"
[ "$(json "$dir/view.json" "d['frames']")" -eq $frames ] || fail "swf-view did not receive every nav_state_t"
[ "$(json "$dir/view.json" "d['bus']['malformed_total'] + d['bus']['lost_total']")" -eq 0 ] || fail "messages malformed or lost"
[ "$(json "$dir/page.json" "d['hazard_known_pixels']")" -gt 1000 ] || fail "hazard map (nearly) empty on the page"
[ "$(json "$dir/view.json" "d['bus']['channels']['SWF_STEREO']['received']")" -eq $frames ] || fail "swf-view did not receive every replayed frame"
# Published, not recorded again: the replay's recording holds its outputs only.
"$(dirname "$replay")/swf-lcmlog" "$dir/replayed.lcmlog" > "$dir/recorded.json"
[ "$(json "$dir/recorded.json" "d['SWF_NAV']['messages']")" -eq $frames ] || fail "the replay did not record its outputs"
[ "$(json "$dir/recorded.json" "'SWF_STEREO' in d")" = False ] || fail "the replay recorded the frames it replayed"
echo PASS
