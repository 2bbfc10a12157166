# Folds the result.csv of a scene made by `scenegen tessellate IN K OUT
# [--tri]` back onto IN's faces: per face of IN, the area-weighted mean of
# its pieces (a quad gives K*K pieces, twice that with --tri; any other
# polygon (n-2)*K*K triangles), written as IN's result.csv would be.
#   awk -v k=K -v tri=0|1 -f tests/fold.awk IN.obj OUT/result.csv
BEGIN { face = 0 }
FNR == NR { if ($1 == "f") { n = NF - 1; pieces[faces++] = n == 4 ? k * k * (tri ? 2 : 1) : (n - 2) * k * k }; next }
FNR == 1 { FS = ","; $0 = $0; print; next }
{
  if (left == 0) { flush(); left = pieces[face]; obj = $2 }
  a += $3; r += $3 * $4; g += $3 * $5; b += $3 * $6; left--
}
function flush() {
  if (a > 0) { printf "%d,%s,%.9g,%.9g,%.9g,%.9g\n", face, obj, a, r / a, g / a, b / a; face++ }
  a = r = g = b = 0
}
END { flush() }
