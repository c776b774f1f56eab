#!/bin/sh
# The flight binary links no simulator, no evaluator and no image decoder (issue 17): none of
# their symbols is in swf-fsw. The same scan of swf-sil must find the simulator's, so an empty
# scan (a stripped binary, a renamed namespace) cannot pass unnoticed.
#   flight_binary_test.sh SWF_FSW SWF_SIL
set -eu
fsw=$1
sil=$2
ground='swf::sim::|swf::sil::|swf::hazard_eval::|stbi_|stbi__'
symbols() { nm -C "$1" | awk '{ $1 = ""; $2 = ""; print }'; }
found=$(symbols "$fsw" | grep -E "$ground" | head -5 || true)
if [ -n "$found" ]; then
  echo "FAIL: swf-fsw links ground code:" >&2
  echo "$found" >&2
  exit 1
fi
for module in 'swf::sim::' 'swf::sil::' 'swf::hazard_eval::'; do
  symbols "$sil" | grep -q "$module" || { echo "FAIL: the scan finds no $module in swf-sil" >&2; exit 1; }
done
echo "swf-fsw: no simulator, evaluator or image-decoder symbols ($(symbols "$fsw" | wc -l) symbols scanned)"
