#!/bin/sh
# make bench: the engine's tables, then the parallel measurements.
#   sh bench/run.sh [all|engine|parallel|quick]     (default: all)
# engine: the shipped scenes at R = 128 and 256 (build/radiosity-bench)
#  column   - mean form-factor column time, split into stages, against the
#             cost model 15 ns/element + 70 ns/covered element + 3 ns/pixel
#  converge - shots and seconds to 1% relative RMS error against the scene's
#             converged solution (epsilon 1e-6), with and without
#             overshooting; master time (select + shoot) per shot
#  Rows also go to bench/results/columns.csv and converge.csv.
# parallel: the paper's section 5 (build/radiosity-parallel, a few minutes):
#  graphs 1-2 from real runs with a worker process of ./radiosity, graphs 3-5
#  from real runs with 1 and 2 worker processes and from the cluster
#  simulation, its validation against the real runs, the targets of issue 4.
#  CSV and SVG go to bench/results/; REPEAT=N sets the real runs per figure
#  (the quickest counts; default 3).
# quick: the parallel part on the room scene only, fewer worker counts and
#  one real run per figure (under a minute), to check a change; its CSV and
#  SVG go to bench/results/tmp/quick/ (not kept in git).
# Timings are from this machine; compare ratios, not absolute times across
# machines, and run it when the machine is otherwise idle.
cd "$(dirname "$0")/.." || exit 1
mkdir -p bench/results
what=${1:-all}
case $what in all|engine|parallel|quick) ;; *) echo "usage: sh bench/run.sh [all|engine|parallel|quick]" >&2; exit 2 ;; esac

if [ "$what" = all ] || [ "$what" = engine ]; then
  out_columns=bench/results/columns.csv
  out_converge=bench/results/converge.csv
  rows=$(mktemp)
  trap 'rm -f "$rows"' EXIT
  for scene in cornell room maze; do
    ./build/radiosity-bench "scenes/$scene.obj" 128 256 >>"$rows" || exit 1
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
  echo
  sh bench/waves.sh
  bash bench/ssh.sh
fi

case $what in
  all|parallel) ./build/radiosity-parallel --repeat "${REPEAT:-3}" ./radiosity bench/results || exit 1 ;;
  quick) ./build/radiosity-parallel --quick --repeat "${REPEAT:-1}" ./radiosity bench/results/tmp/quick || exit 1 ;;
esac
