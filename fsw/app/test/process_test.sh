#!/bin/sh
# The flight process as separate executables on a short simulated descent (config/test.cfg):
#  1. determinism: the live run's recording replayed twice gives bit-identical SWF_NAV,
#     SWF_LANDMARKS and SWF_HAZARD messages, identical to the live run's own outputs (one hazard
#     map per hazard_every = 5 frames: 6 maps);
#  2. a truncated log: swf-replay stops with an error naming the damaged record, after publishing
#     the outputs of every frame before it;
#  3. a bad configuration is refused before start, naming the field.
# usage: process_test.sh SWF-FSW SWF-REPLAY CONFIG
set -eu
fsw=$1 replay=$2 cfg=$3
here=$(dirname "$0")
cmp="/usr/bin/python3 $here/log_compare.py"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

echo "== live run"
"$fsw" --config "$cfg" --set "record.path: $dir/live.lcmlog" || fail "swf-fsw failed"
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
[ "$replayed" -gt 10 ] && [ "$replayed" -lt 30 ] || fail "replayed $replayed frames"
grep -q "the $replayed frames before it were replayed" "$dir/err" ||
  fail "not every frame before the damaged record was processed"

echo "== bad configuration"
printf 'source: sim\nwindow: 99\n' > "$dir/bad.cfg"
rc=0
"$fsw" --config "$dir/bad.cfg" 2> "$dir/err" || rc=$?
cat "$dir/err"
[ "$rc" -eq 2 ] || fail "exit code $rc for a bad configuration"
grep -q "bad.cfg:2: window: 99 is outside \[1, 10\]" "$dir/err" || fail "the field is not named"
rc=0
"$fsw" --config "$cfg" --set "rate_hz: -3" 2> "$dir/err" || rc=$?
[ "$rc" -eq 2 ] && grep -q "rate_hz" "$dir/err" || fail "a bad --set is not refused"
echo "PASS"
