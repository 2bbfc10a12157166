#!/bin/sh
# Surfaces from faces (man page, MESH): the Cornell box and the Blender
# room as shipped and as an exporter writes them, tessellated and
# triangulated (build/scenegen tessellate IN K OUT --tri), each solved with
# the defaults and -j $JOBS. Prints a Markdown table: faces, surfaces,
# patches and elements as built, elements at the end, shots, seconds, and the per-face
# difference from the untessellated scene solved by the same program (the
# pieces folded back onto its faces, area-weighted; per face and channel
# relative to B, faces darker than 1% of the mean compared against that
# 1%; max, and RMS weighted by area).
#   sh bench/surfaces.sh                      this tree's ./radiosity
#   BEFORE=/tmp/before/radiosity sh bench/surfaces.sh   and another build beside it
# JOBS (default 2) workers, K_CORNELL (8) and K_BLENDER (2) the cuts.
cd "$(dirname "$0")/.." || exit 1
JOBS=${JOBS:-2} KC=${K_CORNELL:-8} KB=${K_BLENDER:-2}
for b in radiosity build/scenegen; do
  [ -x "$b" ] || { echo "bench/surfaces.sh: $b missing: make radiosity build/scenegen" >&2; exit 1; }
done
T=$(mktemp -d "${TMPDIR:-/tmp}/surfaces-bench.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
./build/scenegen tessellate scenes/cornell.obj "$KC" "$T/cornell-t.obj" --tri 2>/dev/null || exit 1
./build/scenegen tessellate scenes/blender.obj "$KB" "$T/blender-t.obj" --tri 2>/dev/null || exit 1

# diff A B: "MAX% RMS%" of result.csv A against B (same faces).
diff_csv() {
  awk -F, '
    FNR == 1 { next }
    NR == FNR { a[$1] = $4 " " $5 " " $6; next }
    { b[$1] = $4 " " $5 " " $6; w[$1] = $3; m += $4 + $5 + $6; n += 3 }
    END {
      floor = 0.01 * m / n
      for (f in b) { split(a[f], x, " "); split(b[f], y, " ")
        for (c = 1; c <= 3; c++) { r = (x[c] - y[c]) / (y[c] > floor ? y[c] : floor); if (r < 0) r = -r
          if (r > worst) worst = r; se += w[f] * r * r; sw += w[f] } }
      printf "%.3f%% | %.3f%%", 100 * worst, 100 * sqrt(se / sw) }' "$1" "$2"
}

echo "| program | scene | faces | surfaces | patches | elements | at the end | shots | seconds | per-face diff max | RMS |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
for prog in ./radiosity ${BEFORE:-}; do
  name=$([ "$prog" = ./radiosity ] && echo this || echo before)
  for s in cornell cornell-t blender blender-t; do
    case $s in
      cornell|blender) obj=scenes/$s.obj ;;
      *) obj=$T/$s.obj ;;
    esac
    out=$T/$name-$s
    start=$(date +%s.%N)
    "$prog" -v -j "$JOBS" -o "$out" "$obj" 2>"$out.err" >/dev/null || { echo "$prog $obj failed" >&2; exit 1; }
    secs=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.2f", b - a }')
    # "N faces, [N surfaces,] N patches, N elements": the build before surfaces has no surfaces.
    # shellcheck disable=SC2046 # the four numbers, split on purpose
    set -- $(sed -n 's/^radiosity: \([0-9]*\) faces, \(\([0-9]*\) surfaces, \)\{0,1\}\([0-9]*\) patches, \([0-9]*\) elements.*/\1 \3x \4 \5/p' "$out.err")
    faces=$1 surf=${2%x} patches=$3 elems=$4
    shots=$(tail -1 "$out/log.csv" | cut -d, -f2) end=$(tail -1 "$out/log.csv" | cut -d, -f4)
    case $s in
      cornell-t) awk -v k="$KC" -v tri=1 -f tests/fold.awk scenes/cornell.obj "$out/result.csv" >"$out.csv"
                 d=$(diff_csv "$out.csv" "$T/$name-cornell/result.csv") ;;
      blender-t) awk -v k="$KB" -v tri=1 -f tests/fold.awk scenes/blender.obj "$out/result.csv" >"$out.csv"
                 d=$(diff_csv "$out.csv" "$T/$name-blender/result.csv") ;;
      *) d="- | -" ;;
    esac
    echo "| $name | $s | $faces | ${surf:-(faces)} | $patches | $elems | $end | $shots | $secs | $d |"
  done
done
