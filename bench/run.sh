#!/bin/sh
# make bench: the engine's tables, then the parallel measurements.
#   sh bench/run.sh [all|engine|parallel|quick]     (default: all)
# engine: the shipped scenes at R = 128 and 256 (bench/engine.sh: column
#  times against the cost model, shots and seconds to 1% relative RMS,
#  rows in bench/results/columns.csv and converge.csv), the column at 10^3
#  to 10^6 elements before and after culling (bench/column.sh, rows in
#  bench/results/column-scale.csv), then subdivision
#  and waves (bench/waves.sh) and ssh workers (bench/ssh.sh).
# parallel: the paper's section 5 (build/radiosity-parallel, a few minutes):
#  graphs 1-2 from real runs with a worker process of ./radiosity, graphs 3-5
#  from real runs with 1, 2, 4 ... nproc worker processes and from the cluster
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
  sh bench/engine.sh || exit 1
  echo
  sh bench/column.sh || exit 1
  echo
  sh bench/waves.sh
  bash bench/ssh.sh
fi

case $what in
  all|parallel) ./build/radiosity-parallel --repeat "${REPEAT:-3}" --cores "$(nproc)" ./radiosity bench/results || exit 1 ;;
  quick) ./build/radiosity-parallel --quick --repeat "${REPEAT:-1}" --cores "$(nproc)" ./radiosity bench/results/tmp/quick || exit 1 ;;
esac
