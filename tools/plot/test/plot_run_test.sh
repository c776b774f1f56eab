#!/bin/sh
# The plots of a short simulated descent, as each tool draws them: swf-sil into summary.plot_dir,
# swf-plot from the recorded log (what a replay or a campaign run gets), swf-sim's terrain and
# contact sheet; each PNG checked as an image (png_check). Then a cut log (refused, exit 1) and a
# failing plotter: each tool says which plot failed and why, and exits non-zero.
# usage: plot_run_test.sh SWF_SIL SWF_PLOT SWF_SIM PNG_CHECK CONFIG
set -eu
sil=$1
plot=$2
sim=$3
check=$4
config=$5
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir "$dir/sil" "$dir/log" "$dir/sim" "$dir/bad"
fly() {  # fly FRAMES PLOT_DIR SUMMARY [RECORD]
  "$sil" --config "$config" --set "sim.frames: $1" --set "pacing: lockstep" \
    --set "rt.mlockall: false" --set "rt.priority: 0" --set "lcm.publish: false" \
    --set "summary.plot_dir: $2" --set "summary.path: $3" ${4:+--set "record.path: $4"}
}
fly 20 "$dir/sil" "$dir/summary.json" "$dir/run.lcmlog" 2> "$dir/sil.txt"
"$check" 800 500 "$dir/sil/trajectory.png" "$dir/sil/attitude_error.png" \
  "$dir/sil/landmark_error.png" "$dir/sil/map.png" "$dir/sil/hazard.png" \
  "$dir/sil/terrain_hazard.png"

"$plot" "$dir/run.lcmlog" --out "$dir/log" > "$dir/plot.txt"
"$check" 800 500 "$dir/log/trajectory.png" "$dir/log/attitude_error.png" \
  "$dir/log/landmark_error.png" "$dir/log/map.png" "$dir/log/hazard.png"
# The same run drawn from its log is the same picture swf-sil drew live.
cmp "$dir/sil/trajectory.png" "$dir/log/trajectory.png"
cmp "$dir/sil/hazard.png" "$dir/log/hazard.png"

"$sim" --scenario descent --terrain rocks --frames 4 --every 20 --out "$dir/sim" --no-png 2> "$dir/sim.txt"
"$check" 800 300 "$dir/sim/terrain_hazard.png" "$dir/sim/contact_sheet.png"

# A log cut mid-record: refused with the file named, exit 1 (failed), and no plot drawn.
head -c 5000 "$dir/run.lcmlog" > "$dir/cut.lcmlog"
rc=0
"$plot" "$dir/cut.lcmlog" --out "$dir/cut" 2> "$dir/cut.txt" > /dev/null || rc=$?
[ "$rc" -eq 1 ] || { echo "swf-plot exited $rc on a cut log"; exit 1; }
grep -qF "swf-plot: $dir/cut.lcmlog" "$dir/cut.txt" || { cat "$dir/cut.txt"; exit 1; }
[ -z "$(ls "$dir/cut")" ] || { echo "a refused log left plots:"; ls "$dir/cut"; exit 1; }

# A plotter that fails: named by every tool, with a non-zero exit.
rc=0
SWF_GNUPLOT=false "$plot" "$dir/run.lcmlog" --out "$dir/bad" 2> "$dir/bad.txt" > /dev/null || rc=$?
[ "$rc" -eq 1 ] || { echo "swf-plot exited $rc with a failing plotter"; exit 1; }
grep -q "swf-plot: cannot draw $dir/bad/trajectory.png: false exited with status 1" "$dir/bad.txt" ||
  { cat "$dir/bad.txt"; exit 1; }
rc=0
SWF_GNUPLOT=/nonexistent/gnuplot fly 10 "$dir/bad" "$dir/bad.json" 2> "$dir/bad_sil.txt" || rc=$?
[ "$rc" -eq 1 ] || { echo "swf-sil exited $rc with a missing plotter"; exit 1; }
grep -q "swf-sil: cannot draw $dir/bad/map.png: cannot run /nonexistent/gnuplot" "$dir/bad_sil.txt" ||
  { cat "$dir/bad_sil.txt"; exit 1; }
grep -q '"result": "failed"' "$dir/bad.json" || { echo "the summary does not say failed"; exit 1; }
grep -q 'summary.plot_dir: cannot draw' "$dir/bad.json" || { echo "the summary names no plot"; exit 1; }
[ -z "$(ls "$dir/bad")" ] || { echo "a failed plot left files:"; ls "$dir/bad"; exit 1; }
echo "plots drawn by swf-sil, swf-plot and swf-sim; failing plotters reported"
