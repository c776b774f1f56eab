#!/bin/sh
# swf-judge on a recorded simulated descent: the log carries the truth channels beside the
# estimates (navigation, landmarks, hazard maps), and the judge, reading only the log, gives the
# figures swf-sil's summary gave live.
# Then the failures: a damaged log is named with its record, a log without truth is "not judged".
# usage: judge_log_test.sh SWF_SIL SWF_JUDGE CONFIG
set -eu
sil=$1
judge=$2
config=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$sil" --config "$config" --set "sim.frames: 20" --set "pacing: lockstep" \
  --set "rt.mlockall: false" --set "rt.priority: 0" --set "lcm.publish: false" \
  --set "record.path: $dir/run.lcmlog" --set "summary.path: $dir/summary.json" 2> "$dir/sil.txt"
"$judge" "$dir/run.lcmlog" --json "$dir/judge.json"
python3 - "$dir/summary.json" "$dir/judge.json" <<'PY'
import json, sys
summary = json.load(open(sys.argv[1]))
judge = json.load(open(sys.argv[2]))
nav = judge["navigation"]
marks = judge["landmarks"]
checks = [
    ("outputs", summary["nav_outputs"], nav["outputs_judged"], 0),
    ("pose RMS", summary["pose_rms_error_m"], nav["pose_rms_error_m"], 5e-7),
    ("final pose error", summary["final_pose_error_m"], nav["final_pose_error_m"], 5e-7),
    ("landmark maps", summary["landmark_maps"], marks["maps_judged"], 0),
    ("landmarks evaluated", summary["landmarks_evaluated"], marks["last_map_landmarks_evaluated"], 0),
    ("landmark RMS", summary["landmark_rms_error_m"], marks["last_map_rms_error_m"], 5e-7),
    ("protection violations", summary["integrity"]["protection_violations"],
     judge["integrity"]["protection_violations"], 0),
    ("hazard maps", len(summary["hazard_by_map"]), judge["hazard"]["maps_judged"], 0),
]
live_map = summary["hazard"]
logged_map = judge["hazard"]["last_map"]
for key in ("frame", "known_cells", "rocks_resolved", "rocks_detected", "rock_free_cells",
            "false_rock_cells"):
    checks.append(("final hazard map " + key, live_map[key], logged_map[key], 0))
if summary["safe_site"] is not None:
    checks.append(("safe site clearance", summary["safe_site"]["clearance_to_truth_hazard_m"],
                   logged_map["site"]["clearance_to_truth_hazard_m"], 5e-4))
bad = [c for c in checks if abs(c[1] - c[2]) > c[3]]
for name, live, logged, _ in checks:
    print(f"{name}: live {live}, from the log {logged}")
assert summary["nav_outputs"] > 0 and marks["maps_judged"] > 0, "nothing was judged"
assert judge["hazard"]["maps_judged"] > 0 and judge["hazard"]["maps_without_truth"] == 0
assert judge["result"] == "ok", judge["result"]
sys.exit(1 if bad else 0)
PY
# A log cut inside a record: exit 1, the message names the file and the record.
head -c 5000 "$dir/run.lcmlog" > "$dir/cut.lcmlog"
if "$judge" "$dir/cut.lcmlog" 2> "$dir/cut.txt"; then echo "a cut log was judged"; exit 1; fi
grep -q "cut.lcmlog" "$dir/cut.txt" || { cat "$dir/cut.txt"; exit 1; }
# Estimates without truth (a flight log): exit 1, "not judged", never a score.
python3 - "$dir/run.lcmlog" "$dir/notruth.lcmlog" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
out = bytearray()
pos = 0
while pos < len(data):
    sync, num, ts, clen, dlen = struct.unpack(">IqqII", data[pos:pos + 28])
    end = pos + 28 + clen + dlen
    if not data[pos + 28:pos + 28 + clen].startswith(b"SIM_TRUTH"):
        out += data[pos:end]
    pos = end
open(sys.argv[2], "wb").write(out)
PY
rc=0
"$judge" "$dir/notruth.lcmlog" --json "$dir/notruth.json" 2> /dev/null || rc=$?
[ "$rc" -eq 1 ] || { echo "a log without truth gave exit $rc"; exit 1; }
grep -q '"not judged"' "$dir/notruth.json"
echo "swf-judge: the log gives the live figures; cut and truthless logs refused"
