#!/bin/bash
# The defaults in parallel (issue 17): each scene with the program's
# defaults (subdivision, waves, shooter division), -j 1 then -j J back to
# back, REPEAT pairs (default 3). Ideal: the -j 1 run's CPU time (user +
# sys, master and worker) spread over J cores; "of ideal" is that over
# the -j J run's wall time. The row shown is the median pair by that
# fraction. Then where the -j J run's workers stood idle, in worker-seconds
# as the master reconstructs it (-v, RunResult::idle in scheduler.h):
# in a wave's picture, in division passes, with nothing to select (every
# patch with power owned), otherwise (receiving, shooting, the workers'
# own time outside the form factors), and at the end; and the seconds
# outside the master's loop (start-up and outputs, one core).
# A SCENE is a shipped scene's name or an OBJ file's path; SHOTS, if set,
# stops each run there (-s), for scenes too large to converge in a
# benchmark.
#   bash bench/defaults.sh [SCENE...]     (default: the shipped scenes)
#   BEFORE=/work/base6/radiosity REPEAT=5 bash bench/defaults.sh room
#   build/scenegen boxes 40000 /tmp/b.obj && SHOTS=200 bash bench/defaults.sh /tmp/b.obj
# BEFORE, if set, is another binary run in turn with it, pair by pair
# (the machine is noisy: compare them side by side, not with other
# reports); a binary without the idle line shows "-" there. The load
# average at the start and the end is printed under the table.
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
J=${JOBS:-2}
REPEAT=${REPEAT:-3}
[ $# -gt 0 ] || set -- room maze cornell blender cornell-holes
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
load() { cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo "?"; }
# One run: prints "wall cpu run-seconds idle..." (idle: 5 fields or "-").
run() {  # BINARY JOBS SCENE
  local obj="scenes/$3.obj"
  case $3 in *.obj) obj=$3 ;; esac
  /usr/bin/time -f "TIME %e %U %S" -o "$T/time" "$1" -v -j "$2" ${SHOTS:+-s "$SHOTS"} -o "$T/out" "$obj" \
    2>"$T/err" >/dev/null || { echo "bench/defaults.sh: $1 -j $2 $3 failed" >&2; tail -3 "$T/err" >&2; exit 1; }
  awk '/^TIME/ { w = $2; c = $3 + $4 }
       END { printf "%s %.2f", w, c }' "$T/time"
  awk '/: converged: |: shot limit reached: / { for (i = 1; i < NF; i++) if ($(i + 1) == "s," && $(i - 1) == "in") s = $i }
       /workers idle/ { gsub(/[:;,]/, " "); n = 0
         for (i = 1; i < NF; i++) if ($(i + 1) == "s" && n < 6) v[n++] = $i
         idle = sprintf("%s %s %s %s %s", v[1], v[2], v[3], v[4], v[5]) }
       END { printf " %s %s\n", s == "" ? "-" : s, idle == "" ? "- - - - -" : idle }' "$T/err"
}
started=$(load)
printf '| scene | binary | -j 1 s | -j 1 CPU s | -j %s s | ideal s | of ideal | idle: pictures | passes | nothing to select | otherwise | end | outside the loop s |\n' "$J"
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for s in "$@"; do
  : >"$T/rows"
  for _ in $(seq "$REPEAT"); do
    for b in "$RAD" ${BEFORE:+"$BEFORE"}; do
      one=$(run "$b" 1 "$s") || exit 1
      par=$(run "$b" "$J" "$s") || exit 1
      echo "$b $one $par" >>"$T/rows"
    done
  done
  for b in "$RAD" ${BEFORE:+"$BEFORE"}; do
    # fields: bin w1 c1 s1 i1(5) wJ cJ sJ iJ(5)
    awk -v b="$b" -v j="$J" -v s="$s" 'BEGIN { n = 0 }
      $1 == b {
        ideal = $3 / j; f = ideal / $10
        name = s; sub(/.*\//, "", name)
        row[n] = sprintf("| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %s | %s | %s | %s | %s | %s |",
                         name, b, $2, $3, $10, ideal, f, $13, $14, $15, $16, $17,
                         $12 == "-" ? "-" : sprintf("%.2f", $10 - $12))
        frac[n++] = f }
      END { for (i = 0; i < n; i++) { below = 0
              for (k = 0; k < n; k++) below += frac[k] < frac[i] || (frac[k] == frac[i] && k < i)
              if (below == int((n - 1) / 2)) print row[i] } }' "$T/rows"
  done
done
echo
echo "Load average at the start: $started; at the end: $(load)."
