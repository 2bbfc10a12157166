#!/bin/bash
# Memory and start-up (issue 14): rooms of N boxes (build/scenegen boxes N:
# 7 + 5N faces, about 5 elements a face) run with -j 0 and with -j 1;
# prints peak resident size of the master (-j 0, and the master of -j 1)
# and of the worker, bytes per element, and the load and mesh seconds the
# program prints with -v ("-" for a binary that does not). Two runs a
# binary: 2 shots (--size 64x64), and one of DIVIDE shots (default 52; 0:
# none) at the default picture size, which at 40,000 boxes makes one
# division pass with shooter splits and ends two waves: the run memory.h's
# rates are set from. Its worker's peak is when the worker rebuilds its
# hemicube cache beside the adjacency after edits; whether the second
# wave's splits reach it before the run ends depends on timing, so it
# varies from run to run.
# BEFORE, if set, is another binary run side by side (same scene, back to
# back: the machine is noisy); ARGS, if set, more options for every run
# (ARGS=--no-groups: the figures without shooter groups).
#   bash bench/memory.sh [N...]           (default 200 2000 20000 50000)
#   BEFORE=/tmp/before/radiosity ARGS=--no-groups bash bench/memory.sh 40000
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
GEN=${SCENEGEN:-$PWD/build/scenegen}
DIVIDE=${DIVIDE:-52}
[ -x "$GEN" ] || { echo "bench/memory.sh: $GEN missing: make build/scenegen" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "bench/memory.sh: needs /usr/bin/time (GNU time)" >&2; exit 1; }
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
[ $# -gt 0 ] || set -- 200 2000 20000 50000
# One row: binary, shots, then more options for both runs.
row() {
  local bin=$1 shots=$2
  shift 2
  rm -f "$T/rss0" "$T/rss1" "$T/rssw"
  /usr/bin/time -f '%M' -o "$T/rss0" "$bin" -v -j 0 -s "$shots" "$@" $ARGS -o "$T/o0" "$T/b.obj" 2>"$T/err0"
  /usr/bin/time -f '%M' -o "$T/rss1" "$bin" -q -j 1 -s "$shots" "$@" $ARGS -o "$T/o1" \
    --worker-cmd "/usr/bin/time -f %M -o $T/rssw $bin" "$T/b.obj" 2>/dev/null
  local line faces elems load mesh
  line=$(grep ' patches, .* elements' "$T/err0" | head -1)
  faces=$(echo "$line" | sed -n 's/^radiosity: \([0-9]*\) faces.*/\1/p')
  elems=$(echo "$line" | sed -n 's/.* patches, \([0-9]*\) elements.*/\1/p')
  load=$(echo "$line" | sed -n 's/.*loaded in \([0-9.]*\) s.*/\1/p')
  mesh=$(echo "$line" | sed -n 's/.*meshed in \([0-9.]*\) s.*/\1/p')
  # Division passes, from the -j 0 run's last line ("-" when it has none).
  local passes
  passes=$(sed -n 's/.*; [0-9]* waves, \([0-9]*\) division passes.*/\1/p' "$T/err0" | tail -1)
  # The worker's file: GNU time's last line is the number (a note on
  # the signal that ended it may come first).
  awk -v b="$bin" -v s="$shots" -v p="${passes:--}" -v f="$faces" -v e="$elems" -v l="${load:--}" \
      -v m="${mesh:--}" -v k0="$(tail -1 "$T/rss0")" -v k1="$(tail -1 "$T/rss1")" \
      -v kw="$(tail -1 "$T/rssw")" 'BEGIN {
    printf "| %s | %d | %s | %d | %d | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %s | %s |\n", b, s, p, f, e,
      k0 / 1024, k0 * 1024 / e, k1 / 1024, k1 * 1024 / e, kw / 1024, kw * 1024 / e, l, m }'
}
printf '| binary | shots | division passes | faces | elements | -j 0 MB | B/elem | -j 1 master MB | B/elem | worker MB | B/elem | load s | mesh s |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
for n in "$@"; do
  "$GEN" boxes "$n" "$T/b.obj" >/dev/null 2>&1 || exit 1
  for bin in ${BEFORE:+"$BEFORE"} "$RAD"; do row "$bin" 2 --size 64x64; done
  [ "$DIVIDE" -gt 0 ] || continue
  for bin in ${BEFORE:+"$BEFORE"} "$RAD"; do row "$bin" "$DIVIDE"; done
done
