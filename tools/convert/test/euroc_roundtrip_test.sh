#!/bin/sh
# Acceptance of swf-convert: EuRoC folder -> log -> swf-replay -> TUM trajectory gives the ATE
# swf-eval reports for the same sequence (its SWF run, same window and noise), computed by
# swf-eval's own ScoreTrajectory; then the replay's recording, with its frames, replays again
# with the same trajectory; then the log's pairs come out as PNGs.
#   euroc_roundtrip_test.sh SWF_CONVERT SWF_REPLAY SWF_EVAL EUROC_DIR WORK_DIR
set -eu
convert=$1 replay=$2 evaluate=$3 euroc=$4 work=$5
rm -rf "$work" && mkdir -p "$work"
"$convert" euroc "$euroc" --out "$work/euroc.lcmlog" --calib-out "$work/calib" >/dev/null
cat >"$work/euroc.cfg" <<CFG
source: log
log.path: $work/euroc.lcmlog
camera.left_calibration: $work/calib/left.yaml
camera.right_calibration: $work/calib/right.yaml
pacing: lockstep
rate_hz: 20
mode: swf
window: 5
max_tracks: 150
max_disparity_px: 128
measurement_sigma_px: 0.5
process_sigma_m: 0.05
process_sigma_rad: 0.02
rt.mlockall: false
rt.priority: 0
lcm.publish: false
CFG
"$replay" --config "$work/euroc.cfg" --log "$work/euroc.lcmlog" --record "$work/run.lcmlog" \
  --set 'record.frames: true' 2>"$work/replay.log"
"$convert" trajectory "$work/run.lcmlog" --tum "$work/run_tum.txt" --kitti "$work/run_kitti.txt" >/dev/null
ate=$("$convert" ate --tum "$work/run_tum.txt" --euroc "$euroc" | sed -n 's/.*"ate_rmse_m": \([^,]*\),*/\1/p')
"$evaluate" euroc "$euroc" --out "$work/eval" >/dev/null 2>&1
eval_ate=$(sed -n '/"ate_rmse_m": {/,/}/s/.*"swf": \([^,]*\),*/\1/p' "$work/eval/euroc.json")
echo "round trip ATE $ate m, swf-eval ATE $eval_ate m"
# swf-eval prints 6 significant digits: equal to 1e-9 m.
awk -v a="$ate" -v b="$eval_ate" 'BEGIN { d = a - b; if (d < 0) d = -d; exit !(a > 0 && d < 1e-9) }'
# The recording replays again (it holds the frames) and gives the same trajectory.
"$replay" --config "$work/euroc.cfg" --log "$work/run.lcmlog" --record "$work/run2.lcmlog" 2>/dev/null
"$convert" trajectory "$work/run2.lcmlog" --tum "$work/run2_tum.txt" >/dev/null
cmp "$work/run_tum.txt" "$work/run2_tum.txt"
test "$(wc -l <"$work/run_kitti.txt")" -eq 40
"$convert" pngs "$work/euroc.lcmlog" --out "$work/pngs" >/dev/null
test -s "$work/pngs/left_000039.png" && test -s "$work/pngs/right_000000.png"
echo "round trip ok"
