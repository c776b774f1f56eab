#!/bin/sh
# The flight demo's hazard results (issue 8): swf-fsw on config/demo.cfg (full size: the rock
# field, the orbital target, 512x384, 100 -> 10 m) under lockstep pacing, without LCM, must write
# a summary whose final hazard map has a detection probability over resolved truth rocks and a
# safe site outside the footprint of every truth hazard.
# usage: demo_hazard_test.sh SWF-FSW CONFIG
set -eu
fsw=$1 cfg=$2
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$fsw" --config "$cfg" --set "lcm.publish: false" --set "pacing: lockstep" \
  --set "rt.mlockall: false" --set "rt.priority: 0" --set "summary.path: $dir/summary.json" ||
  { echo "FAIL: swf-fsw failed" >&2; exit 1; }
/usr/bin/python3 - "$dir/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
h, site, target = s["hazard"], s["safe_site"], s["descent_target"]
print("descent target", target)
print("hazard", h)
print("safe site", site)
problems = []
if target["mode"] != "orbital":
    problems.append("the demo no longer flies to the orbital target")
if h is None or h["rocks_resolved"] < 1 or h["detection_probability"] is None:
    problems.append("no resolved truth rock: detection probability is null")
if h is not None and h["false_alarm_rate"] > 0.01:
    problems.append("false-alarm rate %.4f > 0.01" % h["false_alarm_rate"])
if site is None:
    problems.append("no safe site")
elif site["on_truth_hazard"] or site["clearance_to_truth_hazard_m"] <= 1.5:
    problems.append("the safe site is within the 1.5 m footprint of a truth hazard")
for p in problems:
    print("FAIL:", p, file=sys.stderr)
sys.exit(1 if problems else 0)
PY
