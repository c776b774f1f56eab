#!/bin/sh
# The bench's camera configuration (config/bench_gige.cfg) as shipped, on Aravis's GigE Vision
# fake cameras over real GVCP/GVSP on loopback in a private network namespace: swf-fsw serves
# two fakes with the file's serial numbers (LEFT01, RIGHT01) and finds them by serial, applies
# the file's exposure, gain, region of interest, packet size, software trigger and GenICam
# features, and flies 10 frames into output directories that do not exist yet. Checks: 10
# frames, the camera counters in the summary (and in health_t, recorded), the run and its
# configuration echoed; then a GenICam feature the camera does not have stops the start with an
# error naming its configuration key.
# usage: bench_gige_test.sh SWF-FSW
set -eu
fsw=$1
here=$(dirname "$0")
. "$here/fake_gige_env.sh"
cfg="$here/../config/bench_gige.cfg"
bench() {
  in_gige_namespace "$fsw" --config "$cfg" --set "camera.fake: true" \
    --set "camera.left_calibration: $here/../config/fake_gv_left.yaml" \
    --set "camera.right_calibration: $here/../config/fake_gv_right.yaml" \
    --set "max_frames: 10" --set "pacing: lockstep" "$@"
}
rc=0
bench --set "record.path: $dir/new/bench.lcmlog" --set "summary.path: $dir/new/summary.json" \
  2> "$dir/err" || rc=$?
cat "$dir/err"
# The fake cameras show both eyes the same pattern: no stereo, every frame INVALID, exit 1 (the
# plumbing is what is tested here, as in aravis_test.sh).
[ "$rc" -eq 1 ] || fail "swf-fsw exit $rc: expected 1 (no stereo in the fake cameras' pattern)"
s="$dir/new/summary.json"
[ "$(json "$s" "d['source']")" = aravis ] || fail "not the aravis source"
[ "$(json "$s" "d['frames']")" -eq 10 ] || fail "not 10 frames"
for key in missing_packets pairing_failures timeouts; do
  json "$s" "d['camera']['$key'] >= 0" | grep -q True || fail "the summary has no camera.$key"
done
json "$s" "d['run']['config']['keys']['camera.left']['value']" | grep -qx LEFT01 ||
  fail "the summary does not echo camera.left"
json "$s" "d['run']['config']['keys']['camera.fake']['from']" | grep -qx -- --set ||
  fail "the summary does not say camera.fake came from --set"
json "$s" "d['run']['commit']" | grep -q . || fail "the summary has no commit"
[ "$($cmp --count SWF_STEREO "$dir/new/bench.lcmlog")" -eq 10 ] || fail "frames not recorded"
[ "$($cmp --count SWF_HEALTH "$dir/new/bench.lcmlog")" -ge 2 ] || fail "no health_t recorded"
rc=0
bench --set "camera.feature.NoSuchFeature: 1" --set "summary.path: $dir/refused.json" \
  2> "$dir/err" || rc=$?
cat "$dir/err"
[ "$rc" -eq 1 ] || fail "an unknown GenICam feature gave exit $rc, expected 1"
grep -q "GenICam feature NoSuchFeature=1 refused.*configuration key camera.feature.NoSuchFeature at --set" \
  "$dir/err" || fail "the refusal does not name the configuration key"
[ ! -e "$dir/refused.json" ] || fail "a summary was written for a run that did not start"
echo PASS
