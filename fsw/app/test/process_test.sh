#!/bin/sh
# The flight process as separate executables on a short simulated descent (config/test.cfg):
#  1. determinism: the live run's recording replayed twice gives bit-identical SWF_NAV,
#     SWF_LANDMARKS and SWF_HAZARD messages, identical to the live run's own outputs (one hazard
#     map per hazard_every = 5 frames: 6 maps);
#  1b. the same with the simulated MEMS IMU and the stereo-inertial estimator: live and replay
#     bit-identical, every IMU sample the pipeline took recorded (imu_t) and counted;
#  2. a truncated log: swf-replay stops with an error naming the damaged record, after publishing
#     the outputs of every frame before it;
#  3. crafted logs (fsw/app/test/log_mutate.py on the live log's 11th frame): a dropped frame, a
#     duplicated frame and a swapped pair replay to the end and are reported degraded (exit 3)
#     with the count in the summary; a record with num_bytes = -1 stops the replay there (exit 1)
#     naming the record and the field;
#  4. a bad configuration is refused before start, naming the field.
# usage: process_test.sh SWF-FSW SWF-REPLAY CONFIG
set -eu
fsw=$1 replay=$2 cfg=$3
here=$(dirname "$0")
cmp="/usr/bin/python3 $here/log_compare.py"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

echo "== live run"
"$fsw" --config "$cfg" --set "record.path: $dir/live.lcmlog" || fail "swf-sil failed"
echo "== replays"
"$replay" --config "$cfg" --log "$dir/live.lcmlog" --record "$dir/r1.lcmlog" || fail "replay 1"
"$replay" --config "$cfg" --log "$dir/live.lcmlog" --record "$dir/r2.lcmlog" || fail "replay 2"
$cmp SWF_NAV,SWF_LANDMARKS,SWF_HAZARD "$dir/r1.lcmlog" "$dir/r2.lcmlog" "$dir/live.lcmlog" ||
  fail "outputs are not bit-identical"
frames=$($cmp --count SWF_STEREO "$dir/live.lcmlog")
navs=$($cmp --count SWF_NAV "$dir/live.lcmlog")
hazards=$($cmp --count SWF_HAZARD "$dir/live.lcmlog")
[ "$frames" -eq 30 ] && [ "$navs" -eq 30 ] && [ "$hazards" -eq 6 ] ||
  fail "live log holds $frames frames, $navs navs, $hazards hazard maps"

echo "== stereo-inertial: live and replay with the simulated MEMS IMU"
"$fsw" --config "$cfg" --set "sim.imu_unit: mems" --set "imu.enabled: true" \
  --set "record.path: $dir/imu.lcmlog" --set "summary.path: $dir/imu.json" ||
  fail "swf-sil with the IMU failed"
"$replay" --config "$cfg" --set "sim.imu_unit: mems" --set "imu.enabled: true" \
  --log "$dir/imu.lcmlog" --record "$dir/imu_r.lcmlog" || fail "replay with the IMU failed"
$cmp SWF_NAV,SWF_LANDMARKS,SWF_HAZARD "$dir/imu.lcmlog" "$dir/imu_r.lcmlog" ||
  fail "stereo-inertial outputs are not bit-identical"
samples=$($cmp --count SWF_IMU "$dir/imu.lcmlog")
[ "$samples" -eq 1161 ] || fail "the log holds $samples IMU samples, expected 2.9 s at 400 Hz + 1"
grep -q '"imu": {"unit": "mems", "accepted": 1161, "out_of_order": 0' "$dir/imu.json" ||
  fail "the summary does not count the IMU samples"
# The memory figures: every flight thread's stack measured and not past its painted region.
python3 - "$dir/imu.json" <<'PY' || fail "the summary's memory figures are missing or implausible"
import json, sys
m = json.load(open(sys.argv[1]))['memory']
stacks = m['stack_high_water_bytes']
assert all(isinstance(v, int) and 0 < v < m['stack_painted_bytes'] for v in stacks.values()), m
assert not m['stack_saturated'], m
assert 0 < m['resident_bytes_at_start'] <= m['peak_resident_bytes'], m
assert m['minor_faults_after_start'] >= 0 and m['major_faults_after_start'] >= 0, m
PY
$cmp SWF_NAV "$dir/imu.lcmlog" "$dir/live.lcmlog" 2> /dev/null &&
  fail "the IMU run's navigation equals the stereo-only run's"

echo "== truncated log"
size=$(stat -c %s "$dir/live.lcmlog")
head -c $((size * 55 / 100)) "$dir/live.lcmlog" > "$dir/cut.lcmlog"
if "$replay" --config "$cfg" --log "$dir/cut.lcmlog" --record "$dir/r3.lcmlog" 2> "$dir/err"; then
  fail "replay of a truncated log succeeded"
fi
cat "$dir/err"
grep -q "cut.lcmlog: record [0-9]* at byte [0-9]*: truncated" "$dir/err" ||
  fail "the error does not name the record"
replayed=$($cmp --count SWF_NAV "$dir/r3.lcmlog")
# Some frames but not all: the cut lies inside the log (where depends on the record sizes).
[ "$replayed" -gt 0 ] && [ "$replayed" -lt 30 ] || fail "replayed $replayed frames"
grep -q "the $replayed frames before it were replayed" "$dir/err" ||
  fail "not every frame before the damaged record was processed"

echo "== crafted logs"
mutate="/usr/bin/python3 $here/log_mutate.py"
# replay_case OP EXPECTED-EXIT STDERR-PATTERN SUMMARY-PATTERN
replay_case() {
  $mutate "$dir/live.lcmlog" "$dir/$1.lcmlog" SWF_STEREO "$1" 10
  rc=0
  "$replay" --config "$cfg" --log "$dir/$1.lcmlog" --set "summary.path: $dir/$1.json" \
    2> "$dir/err" || rc=$?
  grep "result\|log:" "$dir/err"
  [ "$rc" -eq "$2" ] || fail "$1: exit code $rc, expected $2"
  grep -q "$3" "$dir/err" || fail "$1: stderr lacks '$3'"
  grep -q "$4" "$dir/$1.json" || fail "$1: summary lacks '$4'"
}
replay_case drop 3 "log: 1 frames missing" '"log": {"frames_missing": 1, "duplicates_refused": 0'
grep -q '"frames_dropped": 1,' "$dir/drop.json" || fail "drop: frames_dropped is not 1"
replay_case duplicate 3 "1 duplicated frames refused" '"frames_rejected": 1,'
grep -q '"result": "degraded"' "$dir/duplicate.json" || fail "duplicate: not degraded"
replay_case swap 3 "1 out-of-order frames refused" '"out_of_order_refused": 1}'
replay_case neglen 1 "record [0-9]* (SWF_STEREO, event [0-9]*): .*num_bytes -1: bad length" \
  '"result_reasons": "damaged log"'
grep -q "the 10 frames before it were replayed" "$dir/err" || fail "neglen: frames before it"

echo "== raw frames: the calibrations must be for the log's image size"
# A pinhole calibration for 320x240 px (the fake GigE rig's); the test log is of another size.
calibration="$here/../../../tools/image_io/fuzz/calibration_corpus/pinhole.yaml"
$mutate "$dir/live.lcmlog" "$dir/raw.lcmlog" SWF_STEREO unrectify 0
rc=0
"$replay" --config "$cfg" --log "$dir/raw.lcmlog" --set "camera.left_calibration: $calibration" \
  --set "camera.right_calibration: $calibration" 2> "$dir/err" || rc=$?
cat "$dir/err"
[ "$rc" -eq 2 ] || fail "raw log with a calibration of another size: exit code $rc, expected 2"
grep -q "camera.left_calibration: .*pinhole.yaml is for 320x240 px, the log's frames are" \
  "$dir/err" || fail "the size mismatch is not named"
rc=0
"$replay" --config "$cfg" --log "$dir/raw.lcmlog" 2> "$dir/err" || rc=$?
[ "$rc" -eq 2 ] && grep -q "calibration" "$dir/err" || fail "raw log without calibrations: $rc"

echo "== bad configuration"
printf 'source: sim\nwindow: 99\n' > "$dir/bad.cfg"
rc=0
"$fsw" --config "$dir/bad.cfg" 2> "$dir/err" || rc=$?
cat "$dir/err"
[ "$rc" -eq 2 ] || fail "exit code $rc for a bad configuration"
grep -q "bad.cfg:2: window: 99 is outside \[1, 25\]" "$dir/err" || fail "the field is not named"
rc=0
"$fsw" --config "$cfg" --set "rate_hz: -3" 2> "$dir/err" || rc=$?
[ "$rc" -eq 2 ] && grep -q "rate_hz" "$dir/err" || fail "a bad --set is not refused"
echo "PASS"
