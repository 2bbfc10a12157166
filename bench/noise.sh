#!/bin/sh
# Division by light, not by hemicube noise (issue 15, subdivide.h): element
# counts and error at hemicube resolutions R = 64, 128, 256, 512 on the
# shipped scenes, this build against the program before (BEFORE=path,
# optional), each run -j 0 at default settings but -r R.
# The error is per face, relative RMS (as --reference), on the scene
# tessellated K x K (scenegen tessellate, default K=8): the program joins
# the pieces back into the same surfaces and mesh, and reports each piece,
# so the error is sampled at 1/K of every face's size and not only as
# whole-face means. The reference is the same scene on a uniform mesh of
# patches half the default size and 4 x 4 elements each (elements as
# small as two divisions below the default make), no division, R 512,
# converged to 1e-4 (--converge, -j JOBS); its own distance from a finer
# one is measured by bench/noise.sh REFCHECK=1 (patches a third, R 1024).
# Prints a Markdown table; rows also go to bench/results/noise.csv.
#   BEFORE=/tmp/before2/radiosity sh bench/noise.sh     (about 15 minutes)
#   SCENES="cornell-holes" RES="128 256" sh bench/noise.sh
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
GEN=build/scenegen
K=${K:-8}
SCENES=${SCENES:-"cornell cornell-holes room maze blender"}
RES=${RES:-"64 128 256 512"}
J=${JOBS:-$(nproc 2>/dev/null || echo 2)}
[ -x "$GEN" ] || { echo "bench/noise.sh: $GEN missing: make build/scenegen" >&2; exit 1; }
T=${NOISE_TMP:-bench/results/tmp/noise}
mkdir -p bench/results "$T"
csv=bench/results/noise.csv
echo "scene,resolution,build,elements,rel_rms,seconds" >"$csv"

# The scene's bounding-box diagonal, from its v lines.
diagonal() {
  awk '$1 == "v" { for (i = 0; i < 3; ++i) { x = $(i + 2)
         if (!n || x < lo[i]) lo[i] = x; if (!n || x > hi[i]) hi[i] = x } n = 1 }
       END { print sqrt((hi[0]-lo[0])^2 + (hi[1]-lo[1])^2 + (hi[2]-lo[2])^2) }' "$1"
}

# relrms A.csv REF.csv: results.cpp's RmsError, relative, in percent.
relrms() { awk -F, -f bench/relrms.awk "$2" "$1"; }

# run BINARY OBJ REF OUT R: prints "elements rel_rms seconds" of one run.
run() {
  "$1" -q -j 0 -r "$5" --reference "$3" -o "$4" "$2" 2>"$4.err" >/dev/null
  awk -F, 'END { printf "%d %.3f%% %.1f\n", $4, 100 * $7, $1 }' "$4/log.csv"
}

echo "Elements and error per face piece ($K x $K per face) against a converged fine reference"
echo
echo "| scene | R | elements before | elements after | error before | error after | s before | s after |"
echo "|---|---|---|---|---|---|---|---|"
for s in $SCENES; do
  obj=$T/$s-t$K.obj
  if [ ! -s "$obj" ] || [ "$obj" -ot "scenes/$s.obj" ]; then
    "$GEN" tessellate "scenes/$s.obj" "$K" "$obj" >/dev/null 2>&1 || exit 1
    cp "scenes/$s.mtl" "$T/$s-t$K.mtl"
  fi
  ref=$T/$s-t$K-ref.csv
  d=$(diagonal "scenes/$s.obj")
  if [ ! -s "$ref" ] || [ "$ref" -ot "$obj" ]; then
    "$RAD" -q -j "$J" -r 512 --no-subdivide --patch-size "$(echo "$d" | awk '{ print $1 / 32 }')" \
      --elements 4 -e 1e-4 --converge "$ref" -o "$T/$s-ref" "$obj" || exit 1
  fi
  if [ -n "$REFCHECK" ]; then
    fine=$T/$s-t$K-fine.csv
    [ -s "$fine" ] || "$RAD" -q -j "$J" -r 1024 --no-subdivide \
      --patch-size "$(echo "$d" | awk '{ print $1 / 48 }')" --elements 4 -e 1e-4 \
      --converge "$fine" -o "$T/$s-fine" "$obj" || exit 1
    echo "reference of $s against a finer one: $(relrms "$ref" "$fine")"
    echo
  fi
  for r in $RES; do
    b="- - -"
    [ -n "$BEFORE" ] && b=$(run "$BEFORE" "$obj" "$ref" "$T/$s-$r-before" "$r")
    a=$(run "$RAD" "$obj" "$ref" "$T/$s-$r-after" "$r")
    echo "$b $a" | awk -v s="$s" -v r="$r" -v csv="$csv" '{
      printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", s, r, $1, $4, $2, $5, $3, $6
      if ($1 != "-") printf "%s,%s,before,%s,%s,%s\n", s, r, $1, $2, $3 >>csv
      printf "%s,%s,after,%s,%s,%s\n", s, r, $4, $5, $6 >>csv }'
  done
done
