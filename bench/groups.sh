#!/bin/sh
# Shooter groups (issue 13, groups.h) on generated real-size scenes: a room
# of boxes (scenegen boxes N) and the Cornell box tessellated K x K and
# triangulated (scenegen tessellate scenes/cornell.obj K --tri), of about
# 10^3 and 10^4 faces (10^5 with SIZES="3 4 5", 10^6 with "3 4 5 6"). Each
# scene is run with -j $(nproc) to epsilon 1e-3 under a time limit of
# LIMIT seconds (default 60; BIG_LIMIT, default 120, for 10^5 and 10^6
# faces, so that the table stays affordable): with groups (this build),
# without (--no-groups, the reference), and with the program before
# (BEFORE=path, optional). Prints a Markdown table: faces, surfaces
# (faces joined, surface.h), shooters (groups), patches,
# elements at start and end, shots and seconds to unshot 1e-2 and 1e-3
# (from log.csv; "-" when the limit came first, with where it stood), and
# the per-face relative RMS difference (area-weighted, over the mean, as
# --reference) of the run against the run without groups. Where neither
# converged, that difference holds both runs' own remaining error too.
#   sh bench/groups.sh                         (about 12 minutes at LIMIT=60)
#   SIZES="3 4 5" BEFORE=/tmp/before2/radiosity sh bench/groups.sh
#   BIG_LIMIT=600 SIZES="6" sh bench/groups.sh  (the 10^6 rows: hours)
# Rows also go to bench/results/groups.csv.
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
GEN=build/scenegen
LIMIT=${LIMIT:-60}
BIG_LIMIT=${BIG_LIMIT:-120}
SIZES=${SIZES:-"3 4"}
J=${JOBS:-$(nproc 2>/dev/null || echo 2)}
[ -x "$GEN" ] || { echo "bench/groups.sh: $GEN missing: make build/scenegen" >&2; exit 1; }
T=${GROUPS_TMP:-$(mktemp -d)}
mkdir -p bench/results "$T"
csv=bench/results/groups.csv
echo "scene,faces,surfaces,limit_s,build,shooters,groups,patches,elements_start,elements_end,shots_1e2,s_1e2,shots_1e3,s_1e3,end_s,end_unshot,rel_rms_vs_no_groups" >"$csv"

# relrms A.csv REF.csv: results.cpp's RmsError, relative, in percent.
relrms() { awk -F, -f bench/relrms.awk "$2" "$1"; }

# run NAME BUILD-LABEL BINARY OBJ [OPTIONS]: one run, one table row.
run() {
  name=$1 label=$2 bin=$3 obj=$4; shift 4
  out=$T/$name-$label
  "$bin" -v -j "$J" -e 1e-3 -t "$limit" --log-every 20 -o "$out" "$@" "$obj" 2>"$out.err" >/dev/null
  surfaces=$(sed -n 's/^radiosity: [0-9]* faces, \([0-9]*\) surfaces.*/\1/p' "$out.err" | head -1)
  line=$(grep -E 'converged:|limit reached:|did not converge' "$out.err" | tail -1)
  patches=$(echo "$line" | sed -n 's/.*; \([0-9]*\) patches.*/\1/p')
  e_end=$(echo "$line" | sed -n 's/.* patches, \([0-9]*\) elements.*/\1/p')
  e_start=$(echo "$line" | sed -n 's/.*(\([0-9]*\) built.*/\1/p')
  shooters=$(echo "$line" | sed -n 's/.*; \([0-9]*\) shooters.*/\1/p')
  groups=$(echo "$line" | sed -n 's/.* \([0-9]*\) of them groups.*/\1/p')
  rel=-
  [ "$label" != no-groups ] && [ -s "$out/result.csv" ] && [ -s "$T/$name-no-groups/result.csv" ] &&
    rel=$(relrms "$out/result.csv" "$T/$name-no-groups/result.csv")
  awk -F, -v n="$name" -v f="$faces" -v sf="${surfaces:--}" -v lim="$limit" -v l="$label" -v sh="${shooters:-$patches}" -v g="${groups:-0}" \
      -v p="$patches" -v es="$e_start" -v ee="$e_end" -v rel="$rel" -v csv="$csv" '
    NR > 1 { t = $1; s = $2; u = $5
             if (a == "" && u < 1e-2) { a = s; at = t }
             if (b == "" && u < 1e-3) { b = s; bt = t } }
    END {
      c2 = a == "" ? "-" : sprintf("%d, %.1f s", a, at)
      c3 = b == "" ? sprintf("- (unshot %.2g at %.0f s)", u, t) : sprintf("%d, %.1f s", b, bt)
      printf "| %s | %s | %s | %s | %s (%s) | %s | %s / %s | %s | %s | %s |\n", n, f, sf, l, sh, g, p, es, ee, c2, c3, rel
      printf "%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%.2f,%.3g,%s\n", n, f, sf, lim, l, sh, g, p, es, ee, a, at, b, bt, t, u, rel >> csv
    }' "$out/log.csv"
}

echo "Shooter groups: each scene with \`-j $J -e 1e-3 -t $LIMIT\` (\`-t $BIG_LIMIT\` from 10^5 faces on); shots and seconds to"
echo "unshot 1e-2 and 1e-3 (\"-\": the time limit came first); relative RMS per face against the same build with \`--no-groups\`."
echo
echo "| scene | faces | surfaces | build | shooters (groups) | patches | elements start / end | to 1e-2 | to 1e-3 | rel. RMS vs no groups |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for k in $SIZES; do
  # About 10^k faces: boxes N has 7 + 5 N faces; the Cornell box cut K x K
  # and triangulated 23 x 2 K^2 (its faces are quads).
  case $k in
    3) n=200 t=5 limit=$LIMIT ;; 4) n=2000 t=15 limit=$LIMIT ;;
    5) n=20000 t=47 limit=$BIG_LIMIT ;; 6) n=200000 t=147 limit=$BIG_LIMIT ;;
    *) echo "bench/groups.sh: SIZES are 3..6" >&2; exit 2 ;;
  esac
  [ -s "$T/boxes$n.obj" ] || "$GEN" boxes "$n" "$T/boxes$n.obj" >/dev/null || exit 1
  [ -s "$T/cornell$t.obj" ] || "$GEN" tessellate scenes/cornell.obj "$t" "$T/cornell$t.obj" --tri >/dev/null || exit 1
  for name in "boxes$n" "cornell$t"; do
    faces=$(grep -c '^f ' "$T/$name.obj")
    run "$name" no-groups "$RAD" "$T/$name.obj" --no-groups
    run "$name" groups "$RAD" "$T/$name.obj"
    [ -n "$BEFORE" ] && run "$name" before "$BEFORE" "$T/$name.obj"
  done
done
[ -z "$GROUPS_TMP" ] && rm -rf "$T"
exit 0
