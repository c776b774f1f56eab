#!/bin/sh
# End to end over the network stack: swf-sil and swf-guidance as separate processes talking LCM
# over UDP multicast inside a private network namespace whose only interface is loopback (with a
# multicast route), so nothing ever reaches a real network (RECIPES.md). The flight process flies
# the 30-frame test descent; the consumer must receive every output (sequence numbers checked:
# nothing lost, nothing out of order, nothing malformed; the hazard maps on SWF_HAZARD, ~1.1 MB
# each, included), and the landmark map must be within 1.0 m RMS of the simulator's truth
# (measured: ~0.6 m at 256x192 px from 100 m to 71 m).
# usage: e2e_test.sh SWF-FSW SWF-GUIDANCE CONFIG
set -eu
fsw=$1 guidance=$2 cfg=$3
fail() { echo "FAIL: $*" >&2; exit 1; }
if ! unshare -n true 2>/dev/null; then
  fail "cannot create a network namespace (needs root, or unprivileged user namespaces: unshare -rn)"
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
# The receive buffer holds a whole hazard map (1.1 MB in fragments); rmem_max allows 4 MB.
url="udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304"
unshare -n sh -c '
  set -e
  ip link set lo up
  ip route add 239.0.0.0/8 dev lo
  "$1" --url "$4" --quiet --idle 3 --timeout 120 --map-out "$5/map.txt" > "$5/guidance.json" &
  g=$!
  sleep 0.5
  "$2" --config "$3" --set "lcm.url: $4" --set "lcm.publish: true" \
       --set "summary.path: $5/summary.json" 2> "$5/fsw.err"
  wait $g
' sh "$guidance" "$fsw" "$cfg" "$url" "$dir" || { cat "$dir/fsw.err" >&2; fail "processes failed"; }
cat "$dir/guidance.json"
json() { /usr/bin/python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }
[ "$(json "$dir/guidance.json" "d['nav']['received']")" -eq 30 ] || fail "not every nav_state_t arrived"
[ "$(json "$dir/guidance.json" "d['landmarks']['received']")" -eq 6 ] || fail "not every landmark map arrived"
[ "$(json "$dir/guidance.json" "d['health']['received']")" -ge 3 ] || fail "health messages missing"
[ "$(json "$dir/guidance.json" "d['hazard']['received']")" -eq 6 ] || fail "not every hazard map arrived"
[ "$(json "$dir/guidance.json" "d['hazard']['lost'] + d['hazard']['out_of_order'] + d['hazard']['malformed']")" -eq 0 ] || fail "hazard maps lost, late or malformed"
[ "$(json "$dir/guidance.json" "d['hazard']['last_frame']")" -eq 29 ] || fail "last hazard map missing"
[ "$(json "$dir/guidance.json" "d['nav']['lost'] + d['landmarks']['lost'] + d['health']['lost']")" -eq 0 ] || fail "outputs lost"
[ "$(json "$dir/guidance.json" "d['nav']['out_of_order'] + d['landmarks']['out_of_order']")" -eq 0 ] || fail "out of order"
[ "$(json "$dir/guidance.json" "d['nav']['malformed'] + d['landmarks']['malformed'] + d['health']['malformed']")" -eq 0 ] || fail "malformed"
[ "$(json "$dir/guidance.json" "d['last_frame']")" -eq 29 ] || fail "last frame missing"
[ "$(wc -l < "$dir/map.txt")" -gt 20 ] || fail "landmark map too small"
rms=$(json "$dir/summary.json" "d['landmark_rms_error_m']")
echo "landmark RMS error against truth: $rms m (threshold 1.0 m)"
json "$dir/summary.json" "1 if d['landmark_rms_error_m'] < 1.0 else 0" | grep -q 1 || fail "landmark error $rms m"
echo PASS
