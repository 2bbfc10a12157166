#!/bin/sh
# make bench (first part) and bench/report: the engine's tables
# (build/radiosity-bench) for SCENES (default: cornell room maze) at
# RESOLUTIONS (default: 128 256):
#  column   - mean form-factor column time, split into stages, against the
#             cost model 15 ns/element + 70 ns/covered element + 3 ns/pixel
#  converge - shots and seconds to 1% relative RMS error against the scene's
#             converged solution (epsilon 1e-6), with and without
#             overshooting; master time (select + shoot) per shot
# Tables on stdout; rows to $RESULTS/columns.csv and converge.csv
# (RESULTS defaults to bench/results).
cd "$(dirname "$0")/.." || exit 1
R=${RESULTS:-bench/results}
mkdir -p "$R"
out_columns=$R/columns.csv
out_converge=$R/converge.csv
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
for scene in ${SCENES:-cornell room maze}; do
  # shellcheck disable=SC2086 # a list of numbers
  ./build/radiosity-bench "scenes/$scene.obj" ${RESOLUTIONS:-128 256} >>"$rows" || exit 1
done
echo "Form-factor column (ms per column, means over up to 400 patches)"
echo "| scene | R | elements | covered | column | transform | raster | readback | model | ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|"
grep '^column' "$rows" | sed 's/^column | /| /; s/$/ |/'
echo
echo "To 1% relative RMS (reference: overshooting to epsilon 1e-6)"
echo "| scene | R | method | shots | seconds | master us/shot | reference shots | reference s |"
echo "|---|---|---|---|---|---|---|---|"
grep '^converge' "$rows" | sed 's/^converge | /| /; s/$/ |/'
{
  echo "scene,R,elements,covered,column_ms,transform_ms,raster_ms,readback_ms,model_ms,ratio"
  grep '^column' "$rows" | sed 's/^column | //; s/ | /,/g'
} >"$out_columns"
{
  echo "scene,R,method,shots,seconds,master_us_per_shot,reference_shots,reference_s"
  grep '^converge' "$rows" | sed 's/^converge | //; s/ | /,/g'
} >"$out_converge"
echo
echo "CSV: $out_columns $out_converge"
