#!/bin/sh
# make bench (second part): adaptive subdivision and waves on room and maze.
#  runs  - coarse uniform mesh, adaptive with waves, fine uniform mesh with
#          about as many elements as the adaptive run ends with: elements,
#          waves, shots, seconds, division passes and ms per pass, final
#          error per point against a converged uniform mesh finer than any
#          of them, and when each first reached the fine mesh's final error
#          (seconds, and as a fraction of the fine run's time: the target
#          is at most 0.5 for the adaptive run)
#  graph0-SCENE.svg - paper graph 0: unshot fraction and error against
#          time over the waves of the adaptive run
#  error-SCENE.svg  - error against time of the three runs
# Rows go to bench/results/waves.csv (runs) and curves.csv (samples); set
# RESULTS for another directory, WAVE_SCENES for other scenes (default:
# room maze), REF_ELEMENTS for the reference's elements per patch edge.
cd "$(dirname "$0")/.." || exit 1
R=${RESULTS:-bench/results}
SC=${WAVE_SCENES:-room maze}
mkdir -p $R
REF=${REF_ELEMENTS:-12}
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
echo "scene,method,seconds,shots,wave,elements,unshot_fraction,rel_error" >$R/curves.csv
for scene in $SC; do
  ./build/radiosity-waves "scenes/$scene.obj" $R/curves.csv "$REF" >>"$rows" || exit 1
done
echo "Reference: uniform $REF x $REF elements per patch, epsilon 1e-4"
echo "| scene | elements | shots | seconds |"
echo "|---|---|---|---|"
grep '^reference' "$rows" | sed 's/^reference | /| /; s/$/ |/'
echo
echo "Error per point (FieldError, relative RMS) against the reference; runs to epsilon 1e-3"
echo "| scene | method | elements | waves | shots | seconds | passes | ms/pass | final error | s to fine's final error | / fine's time |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
grep '^run' "$rows" | sed 's/^run | /| /; s/$/ |/'
{
  echo "scene,method,elements,waves,shots,seconds,passes,ms_per_pass,final_rel_error,seconds_to_fine_final,fraction_of_fine_time"
  grep '^run' "$rows" | sed 's/^run | //; s/ | /,/g'
} >$R/waves.csv

# svg FILE TITLE YLABEL SERIES...: a log-y line plot of curves.csv; each
# SERIES is "scene:method:column:colour:label".
svg() {
  file=$1 title=$2 ylabel=$3; shift 3
  awk -F, -v title="$title" -v ylabel="$ylabel" -v series="$*" '
    BEGIN { ns = split(series, S, " ")
      for (i = 1; i <= ns; i++) { split(S[i], f, ":"); sc[i] = f[1]; me[i] = f[2]; co[i] = f[3]; col[i] = f[4]; lab[i] = f[5]; gsub(/_/, " ", lab[i]) } }
    NR == 1 { for (k = 1; k <= NF; k++) idx[$k] = k; next }
    { for (i = 1; i <= ns; i++) if ($1 == sc[i] && $2 == me[i]) {
        v = $(idx[co[i]]); if (v <= 0) continue
        n[i]++; X[i, n[i]] = $3; Y[i, n[i]] = log(v) / log(10); W[i, n[i]] = $5
        if ($3 > xmax) xmax = $3; if (!seen++ || Y[i, n[i]] < ymin) ymin = Y[i, n[i]]; if (seen == 1 || Y[i, n[i]] > ymax) ymax = Y[i, n[i]] } }
    END {
      ymin = int(ymin - 1); ymax = int(ymax + 1); if (ymax > 0) ymax = 0.5; if (xmax <= 0) xmax = 1
      w = 640; h = 400; L = 60; T = 30; PW = w - L - 20; PH = h - T - 50
      printf "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" font-family=\"sans-serif\" font-size=\"12\">\n", w, h
      printf "<rect width=\"%d\" height=\"%d\" fill=\"white\"/>\n<text x=\"%d\" y=\"18\" font-size=\"14\">%s</text>\n", w, h, L, title
      printf "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" stroke=\"black\"/>\n", L, T, PW, PH
      for (e = ymin; e <= ymax; e++) { y = T + PH * (ymax - e) / (ymax - ymin)
        printf "<line x1=\"%d\" x2=\"%d\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/><text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">1e%d</text>\n", L, L + PW, y, y, L - 4, y + 4, e }
      for (k = 0; k <= 5; k++) { x = L + PW * k / 5
        printf "<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%.3g</text>\n", x, T + PH + 16, xmax * k / 5 }
      printf "<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">seconds</text>\n", L + PW / 2, h - 12
      printf "<text x=\"14\" y=\"%d\" transform=\"rotate(-90 14 %d)\" text-anchor=\"middle\">%s</text>\n", T + PH / 2, T + PH / 2, ylabel
      for (i = 1; i <= ns; i++) {
        pts = ""; last = W[i, 1]
        for (j = 1; j <= n[i]; j++) {
          x = L + PW * X[i, j] / xmax; y = T + PH * (ymax - Y[i, j]) / (ymax - ymin)
          if (W[i, j] != last) {  # a new wave: break the line, mark it
            printf "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"%s\"/>\n", col[i], pts; pts = ""
            printf "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%d\" y2=\"%d\" stroke=\"#bbb\" stroke-dasharray=\"3,3\"/>\n", x, x, T, T + PH
            last = W[i, j] }
          pts = pts sprintf("%.1f,%.1f ", x, y) }
        printf "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"%s\"/>\n", col[i], pts
        printf "<text x=\"%d\" y=\"%d\" fill=\"%s\">%s</text>\n", L + PW - 200, T + 16 * i, col[i], lab[i] }
      print "</svg>" }' $R/curves.csv >"$file"
}
for scene in $SC; do
  svg $R/graph0-$scene.svg "Graph 0, $scene: adaptive with waves (dashed: a new wave)" "fraction" \
    "$scene:adaptive:unshot_fraction:#c00:unshot_fraction" "$scene:adaptive:rel_error:#00c:relative_RMS_error"
  svg $R/error-$scene.svg "$scene: relative RMS error per point against time" "relative error" \
    "$scene:coarse:rel_error:#888:coarse_uniform" "$scene:fine:rel_error:#080:fine_uniform" \
    "$scene:adaptive:rel_error:#c00:adaptive_with_waves"
done
echo
echo "CSV: $R/waves.csv $R/curves.csv; SVG: $(for s in $SC; do printf '%s ' "$R/graph0-$s.svg" "$R/error-$s.svg"; done)"
