#!/bin/sh
# swf-view under what it must survive (real processes, LCM UDP multicast in a private network
# namespace): view_stress_publisher sends two 20 Hz flights of 1024 x 768 stereo frames with
# navigation outputs and hazard maps, malformed messages mixed in, and a silence between the
# flights (the publisher stops, then restarts from sequence 0), while a slow browser backs up
# its event stream and a poller reads /state.json five times a second. swf-view must stay up and
# answer throughout, count every malformed message, see both restarts, call the publisher silent
# during the pause, and report the images it skipped (latest wins) and any sequence gaps.
# usage: view_robustness_test.sh SWF-VIEW STRESS-PUBLISHER SLOW_CLIENTS
set -eu
view=$1 publisher=$2 clients=$3
export private_network_sh="$(cd "$(dirname "$0")/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
choose_private_network || fail "cannot create a network namespace (root or unprivileged user namespaces)"
make_scratch_dir
$ns sh -c '
  set -e
  . "$private_network_sh"
  multicast_on_loopback
  start_view "$1" "$4"
  /usr/bin/python3 "$3" "$url" "$4/stop" > "$4/clients.json" &
  c=$!
  "$2" --frames 40 --rate 20 --pause 2.5 --width 1024 --height 768 > "$4/publisher.json"
  sleep 0.5
  touch "$4/stop"
  wait $c
  kill -0 $v || { echo "swf-view died" >&2; exit 1; }
  /usr/bin/python3 -c "import urllib.request,sys; print(urllib.request.urlopen(sys.argv[1] + \"healthz\").read().decode().strip())" "$url" > "$4/healthz"
  kill -TERM $v; wait $v
' sh "$view" "$publisher" "$clients" "$dir" || { cat "$dir/view.err" >&2; fail "swf-view did not hold up"; }
echo "publisher: $(cat "$dir/publisher.json")"
echo "clients: $(cat "$dir/clients.json")"
echo "swf-view: $(cat "$dir/view.json")"
[ "$(cat "$dir/healthz")" = ok ] || fail "swf-view did not answer at the end"
sent_bad=$(json "$dir/publisher.json" "d['malformed']")
[ "$(json "$dir/view.json" "d['bus']['malformed_total']")" -eq "$sent_bad" ] || fail "malformed messages not all counted ($sent_bad sent)"
for ch in SWF_NAV SWF_STEREO SWF_HAZARD SWF_FEATURES; do
  [ "$(json "$dir/view.json" "d['bus']['channels']['$ch']['restarts']")" -eq 1 ] || fail "$ch: the restart was not seen"
done
frames=$(json "$dir/publisher.json" "d['frames']")
got=$(json "$dir/view.json" "d['bus']['channels']['SWF_STEREO']['received'] + d['bus']['channels']['SWF_STEREO']['lost']")
[ "$got" -le "$frames" ] && [ "$got" -ge $((frames - 2)) ] || fail "frames received + reported lost ($got) do not account for the $frames sent"
[ "$(json "$dir/view.json" "d['bus']['images_superseded']")" -gt 0 ] || fail "no image skipped: latest-wins not exercised"
[ "$(json "$dir/clients.json" "d['poll_failures']")" -eq 0 ] || fail "the state did not always answer"
[ "$(json "$dir/clients.json" "d['saw_silent'] and d['saw_live']")" = True ] || fail "the silence was not reported"
[ "$(json "$dir/clients.json" "d['slow_events']")" -gt 0 ] || fail "the slow client got nothing"
echo PASS
