#!/bin/sh
# Shooter division (--split; man page, SUBDIVISION): a cube on a table top
# under a ceiling light (bench/make_table.py). The cube's and the table
# top's mean red radiosity, --no-split against the default (shooter
# division), each against a
# reference with patches REF_DIV times smaller (default 4) and one element
# per patch, to -e 1e-4, and the reference's own refinement (2 x REF_DIV)
# when REFINE=1 (hours on a loaded machine). Prints a Markdown table.
#   sh bench/shooters.sh        (RADIOSITY=./radiosity, JOBS=0)
set -u
cd "$(dirname "$0")/.." || exit 1
BIN=${RADIOSITY:-./radiosity}
JOBS=${JOBS:-0}
REF_DIV=${REF_DIV:-4}
W=$(mktemp -d "${TMPDIR:-/tmp}/shooters.XXXXXX") || exit 1
trap 'rm -rf "$W"' EXIT
python3 bench/make_table.py "$W/table.obj" || exit 1
# The default patch size: the bounding-box diagonal / 16 (man page, MESH).
P=$(awk '/^v / { for (i = 2; i <= 4; i++) { if (!(i in lo) || $i < lo[i]) lo[i] = $i
                   if (!(i in hi) || $i > hi[i]) hi[i] = $i } }
         END { d = 0; for (i = 2; i <= 4; i++) d += (hi[i] - lo[i]) ^ 2; printf "%.9g", sqrt(d) / 16 }' "$W/table.obj")
# measure DIR: the cube's area-weighted and the table top's (its first face) B_r.
measure() {
  awk -F, 'NR > 1 && $2 == "Cube" { a += $3; b += $3 * $4 }
           NR > 1 && $2 == "TableTop" && !t { t = $4 }
           END { printf "%.5f %.5f\n", b / a, t }' "$1/result.csv"
}
# run NAME ARGS...: seconds and patches of one run into $W/NAME.
run() {
  name=$1; shift
  t0=$(date +%s.%N)
  "$BIN" -v -j "$JOBS" -o "$W/$name" "$@" "$W/table.obj" 2>"$W/$name.err" >/dev/null
  t1=$(date +%s.%N)
  echo "$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }') $(sed -n 's/^radiosity: .*; \([0-9]*\) patches, .*/\1/p' "$W/$name.err") $(measure "$W/$name")"
}
ref=$(run ref -e 1e-4 --patch-size "$(awk -v p="$P" -v k="$REF_DIV" 'BEGIN { print p / k }')" --elements 1)
set -- $ref
rc=$3 rt=$4
echo "| run | patches at the end | seconds | cube B_r | error | table top B_r | error |"
echo "|---|---|---|---|---|---|---|"
row() {  # NAME RESULT
  set -- "$1" $2
  awk -v n="$1" -v s="$2" -v p="$3" -v c="$4" -v t="$5" -v rc="$rc" -v rt="$rt" 'BEGIN {
    printf "| %s | %s | %s | %.4f | %+.2f%% | %.4f | %+.2f%% |\n", n, p, s, c, 100 * (c - rc) / rc, t, 100 * (t - rt) / rt }'
}
row "reference (patches / $REF_DIV, 1 element, -e 1e-4)" "$ref"
if [ "${REFINE:-0}" = 1 ]; then
  row "its refinement (patches / $((2 * REF_DIV)))" "$(run fine -e 1e-4 --patch-size "$(awk -v p="$P" -v k="$REF_DIV" 'BEGIN { print p / k / 2 }')" --elements 1)"
fi
row "--no-split" "$(run nosplit --no-split)"
row "default (shooter division)" "$(run default)"
