#!/bin/sh
# Bytes on the wire per non-zero form factor (issue 17, "Fewer bytes"):
# build/radiosity-ffbytes on the shipped scenes at R 64 and 256 and on a
# room of 3,800 boxes (about 10^5 elements) at R 256, the encoding sent
# now (protocol 7) against protocol 5's size, general compressors on each
# frame and entropy bounds for the codes, as one Markdown table on stdout.
#   sh bench/ffbytes.sh            (SHOTS, default 300: columns per scene)
cd "$(dirname "$0")/.." || exit 1
for b in build/radiosity-ffbytes build/scenegen; do
  [ -x "$b" ] || { echo "bench/ffbytes.sh: $b missing: make $b" >&2; exit 1; }
done
S=bench/results/tmp/scenes
mkdir -p "$S"
[ -s "$S/boxes3800.obj" ] || ./build/scenegen boxes 3800 "$S/boxes3800.obj" >/dev/null || exit 1
SHOTS=${SHOTS:-300}
echo "| scene | R | columns | form factors/column | encoding | bytes/form factor | of now | worker encode ns/form factor | master decode ns/form factor |"
echo "|---|---|---|---|---|---|---|---|---|"
for s in cornell room maze blender cornell-holes; do
  for r in 64 256; do
    ./build/radiosity-ffbytes "scenes/$s.obj" "$SHOTS" "$r" || exit 1
  done
done
./build/radiosity-ffbytes "$S/boxes3800.obj" "$SHOTS" 256 || exit 1
