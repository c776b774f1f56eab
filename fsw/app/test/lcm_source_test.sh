#!/bin/sh
# swf-fsw with `source: lcm` end to end: inside a private network namespace (loopback only, a
# multicast route on it) a separate publisher process (lcm_stereo_publisher) sends raw 320x240
# stereo_frame_t pairs of a textured plane at 10 Hz on CAM_STEREO over real UDP multicast, and
# swf-fsw receives them through LcmStereoSource, rectifies them with the rig's calibrations
# (config/fake_gv_*.yaml) and flies 20 frames. The publisher starts first and sends until swf-fsw,
# having answered, falls silent (1 s), so frames sent before swf-fsw subscribed are simply never
# seen (no start-up race). After the first answer it sends one junk message: counted as rejected, which
# the verdict must say (1 of 20 frames is over the 1 % loss bound: not ok).
# Checks: 20 frames flown, 20 nav_state_t and 4 hazard maps recorded, the junk rejected and
# named, at most a few counted drops (a loaded machine may fill the pool), zero allocations on
# the real-time threads, the verdict and the exit code agree.
# usage: lcm_source_test.sh SWF-FSW LCM-STEREO-PUBLISHER
set -eu
fsw=$1 pub=$2
here=$(dirname "$0")
export private_network_sh="$(cd "$here/../../../tests/support/sh" && pwd)/private_network.sh"
. "$private_network_sh"
choose_private_network || fail "cannot create a network namespace (root or unprivileged userns)"
make_scratch_dir
cat > "$dir/lcm.cfg" <<CFG
source: lcm
lcm_source.channel: CAM_STEREO
lcm_source.buffers: 16
camera.left_calibration: $here/../config/fake_gv_left.yaml
camera.right_calibration: $here/../config/fake_gv_right.yaml
rate_hz: 10
pacing: lockstep
window: 5
max_tracks: 100
max_disparity_px: 64
hazard_every: 5
health_every: 5
max_frames: 20
rt.mlockall: false
rt.priority: 0
initial: position
initial.position_m: 0 0 10
# The textured plane is 300 px x 0.2 m / 8 px = 7.5 m away.
envelope.min_range_m: 5
record.path: $dir/live.lcmlog
summary.path: $dir/summary.json
CFG
"$fsw" --config "$dir/lcm.cfg" --check || fail "the configuration is refused"
url="udpm://239.255.76.67:7667?ttl=0"
# fly TAG CONFIG PUBLISHER-ARGS...: inside the namespace, the publisher (URL, then its arguments)
# and swf-fsw on CONFIG; sets rc (swf-fsw's exit) and prc (the publisher's); their stderr is kept
# in $dir/TAG.err and $dir/TAG.pub.err.
fly() {
  tag=$1 cfg=$2
  shift 2
  $ns sh -c '. "$private_network_sh"; multicast_on_loopback || exit 9
    fsw=$1 pub=$2 cfg=$3 url=$4 out=$5
    shift 5
    "$pub" "$url" "$@" 2> "$out.pub.err" & p=$!
    rc=0; "$fsw" --config "$cfg" 2> "$out.err" || rc=$?
    prc=0; wait $p || prc=$?
    echo "$rc $prc" > "$out.rc"' sh "$fsw" "$pub" "$cfg" "$url" "$dir/$tag" "$@"
  cat "$dir/$tag.err" "$dir/$tag.pub.err"
  read -r rc prc < "$dir/$tag.rc"
}
fly stereo "$dir/lcm.cfg" CAM_STEREO SWF_NAV 320 240 20 --junk
[ "$prc" -eq 0 ] || fail "the publisher did not see 20 nav_state_t (exit $prc)"
result=$(json "$dir/summary.json" "d['result']")
case "$result:$rc" in ok:0|degraded:3|failed:1) ;; *) fail "result $result with exit $rc" ;; esac
[ "$result" != ok ] || fail "a rejected message on the channel went unreported (result ok)"
[ "$(json "$dir/summary.json" "d['source']")" = lcm ] || fail "not the lcm source"
[ "$(json "$dir/summary.json" "d['frames']")" -eq 20 ] || fail "not 20 frames"
[ "$(json "$dir/summary.json" "d['frames_rejected']")" -eq 1 ] || fail "the junk message was not counted"
dropped=$(json "$dir/summary.json" "d['frames_dropped']")
echo "frames dropped (counted): $dropped"
[ "$dropped" -le 5 ] || fail "$dropped frames dropped"
[ "$(json "$dir/summary.json" "d['allocations_after_start']")" -eq 0 ] || fail "real-time allocations"
grep -q "lcm CAM_STEREO: .* 20 pairs served; 1 rejected (1 undecodable" "$dir/stereo.err" ||
  fail "the source's counts are not reported"
cmp="/usr/bin/python3 $here/log_compare.py"
[ "$($cmp --count SWF_STEREO "$dir/live.lcmlog")" -eq 20 ] || fail "frames not recorded"
[ "$($cmp --count SWF_NAV "$dir/live.lcmlog")" -eq 20 ] || fail "not 20 nav_state_t"
[ "$($cmp --count SWF_HAZARD "$dir/live.lcmlog")" -eq 4 ] || fail "not 4 hazard maps"
echo "PASS: stereo over LCM"

# Then stereo-inertial: the same publisher is also the IMU (imu_t at 200 Hz on CAM_IMU, the rig
# standing still) and swf-fsw takes both from the bus (LcmImuInput beside LcmStereoSource), levels
# its start on the static IMU (gravity, zero velocity, gyroscope bias) and flies the 20 frames on
# the preintegrated IMU, VALID once levelled.
cp "$dir/lcm.cfg" "$dir/imu.cfg"
cat >> "$dir/imu.cfg" <<CFG
imu.enabled: true
imu.channel: CAM_IMU
imu.rate_hz: 200
imu.static_start: true
# A bench on Earth (the default is the Moon's).
imu.gravity_mps2: 9.81
CFG
sed -i -e "s#^record.path: .*#record.path: $dir/imu.lcmlog#" \
  -e "s#^summary.path: .*#summary.path: $dir/imu.json#" "$dir/imu.cfg"
"$fsw" --config "$dir/imu.cfg" --check || fail "the stereo-inertial configuration is refused"
fly imu "$dir/imu.cfg" CAM_STEREO SWF_NAV 320 240 17 --imu CAM_IMU
[ "$prc" -eq 0 ] || fail "stereo-inertial: the publisher saw fewer than 17 nav_state_t (exit $prc)"
result=$(json "$dir/imu.json" "d['result']")
echo "stereo-inertial: result $result, exit $rc"
case "$result:$rc" in ok:0|degraded:3|failed:1) ;; *) fail "result $result with exit $rc" ;; esac
[ "$(json "$dir/imu.json" "d['frames']")" -eq 20 ] || fail "stereo-inertial: not 20 frames"
accepted=$(json "$dir/imu.json" "d['imu']['accepted']")
echo "IMU samples accepted: $accepted"
[ "$accepted" -ge 360 ] || fail "stereo-inertial: only $accepted IMU samples fused"
[ "$(json "$dir/imu.json" "d['imu']['static_start']")" -eq 1 ] || fail "no static start"
# The first pairs may come before 50 samples of rest (250 ms): INVALID until the static start.
invalid=$(json "$dir/imu.json" "d['integrity']['frames_invalid']")
valid=$(json "$dir/imu.json" "d['integrity']['frames_valid']")
echo "stereo-inertial: $valid VALID, $invalid INVALID (waiting for the static start)"
[ "$invalid" -le 3 ] || fail "$invalid INVALID frames"
[ "$valid" -ge 15 ] || fail "only $valid VALID frames"
[ "$(json "$dir/imu.json" "d['allocations_after_start']")" -eq 0 ] || fail "real-time allocations"
[ "$($cmp --count SWF_IMU "$dir/imu.lcmlog")" -eq "$accepted" ] || fail "IMU samples not recorded"
echo PASS
