#!/bin/sh
# swf-spy lists every channel: lcm-spy, started by the launcher's own code (SwfSpy.start, inside
# SpyCheck) under Xvfb, and swf-sil publishing a short demo descent (real-time pacing, recording,
# so SWF_STEREO goes out too) as separate processes over LCM UDP multicast in a private network
# namespace whose only interface is loopback (RECIPES.md). When the flight ends, the channels,
# types and message counts of its recording (read by swf-lcmlog) are handed to SpyCheck, which
# passes when lcm-spy's channel table shows every one of them with its type decoded, every
# message counted and none undecodable. The window's screenshot is kept (argument 5).
# Exit 77 (ctest: skipped) only when this machine cannot make a network namespace.
# usage: spy_test.sh SWF-SIL CONFIG SWF-LCMLOG "SPYCHECK-COMMAND" SCREENSHOT_OUT
set -eu
sil=$1 cfg=$2 lcmlog=$3 check=$4 shot=$5
export private_network_sh="$(cd "$(dirname "$0")/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
if ! choose_private_network; then
  echo "SKIP: cannot create a network namespace (needs root or unprivileged user namespaces)"
  exit 77
fi
command -v xvfb-run >/dev/null || fail "xvfb-run is not installed (tools/run installs xvfb)"
make_scratch_dir
frames=10
$ns sh -c '
  set -e
  . "$private_network_sh"
  multicast_on_loopback
  xvfb-run -a -s "-screen 0 1280x800x24" $4 "$5/ready" "$5/expected" "$6" 90 \
    > "$5/spy.out" 2> "$5/spy.err" &
  c=$!
  for i in $(seq 600); do
    [ -e "$5/ready" ] || ! kill -0 $c 2>/dev/null && break
    sleep 0.1
  done
  [ -e "$5/ready" ] || { echo "lcm-spy did not start" >&2; exit 1; }
  "$1" --config "$2" --set "pacing: realtime" --set "rt.mlockall: false" --set "rt.priority: 0" \
       --set "sim.frames: $7" --set "lcm.publish: true" --set "record.path: $5/descent.lcmlog" \
       --set "summary.path: $5/summary.json" 2> "$5/sil.err" || echo "swf-sil exit $?" >&2
  "$3" "$5/descent.lcmlog" > "$5/recorded.json"
  # SWF_IMU is recorded, not published: the IMU owns that channel (fsw/app/src/lcm_io.cpp).
  /usr/bin/python3 -c "import json, sys
for c, v in json.load(open(sys.argv[1])).items():
    if c != \"SWF_IMU\": print(c, v[\"type\"], v[\"messages\"])" \
    "$5/recorded.json" > "$5/expected.new"
  mv "$5/expected.new" "$5/expected"
  wait $c
' sh "$sil" "$cfg" "$lcmlog" "$check" "$dir" "$shot" "$frames" || {
  cat "$dir/spy.out" "$dir/spy.err" "$dir/sil.err" >&2; fail "lcm-spy did not list every channel"; }
cat "$dir/spy.out"
[ -s "$shot" ] || fail "no screenshot of lcm-spy's window"
echo PASS
