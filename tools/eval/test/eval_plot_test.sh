#!/bin/sh
# swf-eval's figures as `tools/run eval` draws them: Fig. 12 from a one-run `swf-eval paper`, its
# .dat carrying the figure's title, axis labels and scale, drawn by `swf-plot curves` and checked
# as an image (png_check). Then malformed .dat files: each refused with its file and line named,
# exit 1, and no PNG; a good file beside them is still drawn.
# usage: eval_plot_test.sh SWF_EVAL SWF_PLOT PNG_CHECK
set -eu
eval_tool=$1
plot=$2
check=$3
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail() { echo "FAILED: $*"; exit 1; }

"$eval_tool" paper "$dir" --runs 1 --only fig12 > "$dir/eval.txt"
dat=$dir/fig12_static.dat
grep -q '^# title: Fig. 12: landmark error with static cameras, 30 landmarks (1 run)$' "$dat" ||
  fail "no figure title in $dat: $(head -1 "$dat")"
grep -q '^# x: frame number$' "$dat" || fail "no x label in $dat"
grep -q '^# y: landmark mean squared error (m^2)$' "$dat" || fail "no y label in $dat"
grep -q '^# y scale: log$' "$dat" || fail "no log scale in $dat"
grep -q '^# series: "SWF(5)" "1/m" "CRLB"$' "$dat" || fail "no series names in $dat"
"$plot" curves "$dat" > "$dir/plot.txt"
[ "$(cat "$dir/plot.txt")" = "$dir/fig12_static.png" ] || fail "swf-plot printed $(cat "$dir/plot.txt")"
"$check" 1000 600 "$dir/fig12_static.png"

# Malformed files: the old header without title and labels, a short row, a word for a number.
mkdir "$dir/bad" "$dir/png"
printf '# frame "a" "b"\n1 2 3\n' > "$dir/bad/old.dat"
header='# title: t\n# x: frame number\n# y: error (m)\n# y scale: linear\n# series: "a" "b"\n'
printf "$header"'1 2 3\n2 4\n' > "$dir/bad/short.dat"
printf "$header"'1 2 3\n2 4 five\n' > "$dir/bad/word.dat"
cp "$dat" "$dir/bad/good.dat"
rc=0
"$plot" curves "$dir/bad/old.dat" "$dir/bad/short.dat" "$dir/bad/good.dat" "$dir/bad/word.dat" \
  --out "$dir/png" > "$dir/bad.txt" 2> "$dir/bad_err.txt" || rc=$?
cat "$dir/bad_err.txt"
[ "$rc" -eq 1 ] || fail "swf-plot curves exited $rc on malformed files"
grep -qF "swf-plot curves: $dir/bad/old.dat:1: expected a header line '# KEY: VALUE'" \
  "$dir/bad_err.txt" || fail "the old header is not named"
grep -qF "swf-plot curves: $dir/bad/short.dat:7: expected 3 numbers (x and 2 series), found 2" \
  "$dir/bad_err.txt" || fail "the short row is not named"
grep -qF "swf-plot curves: $dir/bad/word.dat:7: column 3: 'five' is not a number" \
  "$dir/bad_err.txt" || fail "the word is not named"
[ "$(ls "$dir/png")" = good.png ] || fail "expected only good.png, found: $(ls "$dir/png")"
"$check" 1000 600 "$dir/png/good.png"
echo "Fig. 12 drawn from its .dat with its title and labels; malformed .dat files named by line"
