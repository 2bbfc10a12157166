# awk -F, -f bench/relrms.awk REF.csv A.csv: the relative RMS difference
# of result.csv A from REF (results.cpp's RmsError over the area-weighted
# mean of REF), in percent; "-" for a dark REF.
FNR == 1 { next }
NR == FNR { r[$1] = $4; g[$1] = $5; b[$1] = $6; next }
{ a = $3; dr = $4 - r[$1]; dg = $5 - g[$1]; db = $6 - b[$1]
  se += a * (dr * dr + dg * dg + db * db) / 3; m += a * (r[$1] + g[$1] + b[$1]) / 3; A += a }
END { if (m > 0) printf "%.3f%%", 100 * sqrt(se / A) / (m / A); else print "-" }
