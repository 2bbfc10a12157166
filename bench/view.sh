#!/bin/sh
# What the browser view (--view) costs the master: each scene run with
# -j 0 (the master computes and shoots alone, so anything that slows it
# shows in its shots per second) for SHOTS shots, without --view, with
# --view and no browser, and with --view and headless Chromium watching
# the page (skipped without Chromium; on this machine the browser's
# software WebGL shares the cores with the run, which the first two rows
# do not have). REPEAT rounds, the three one after the other in each, so
# that a noisy machine hits them alike. Prints a Markdown table: shots per
# second, and, from the -v summary, the mesh snapshots taken, their mean
# and largest cost and their share of the run.
#   sh bench/view.sh                                   (about a minute)
#   SCENES="scenes/room.obj /tmp/g/boxes1k.obj" SHOTS=500 sh bench/view.sh
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
SCENES=${SCENES:-scenes/room.obj}
SHOTS=${SHOTS:-1500}
REPEAT=${REPEAT:-2}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
browser=no
command -v chromium >/dev/null 2>&1 && browser=yes

# watch URL PID: headless Chromium on the page until process PID ends.
watch() {
  python3 - "$1" "$2" <<'EOF'
import os, sys, time
sys.path.insert(0, "tests")
sys.dont_write_bytecode = True
from cdp import Browser
with Browser() as b:
    b.viewport(960, 600)
    b.open(sys.argv[1])
    while True:
        try:
            os.kill(int(sys.argv[2]), 0)
        except OSError:
            break
        time.sleep(0.1)
EOF
}

# run SCENE MODE: one run; prints "shots/s snapshots ms_each ms_max percent".
run() {
  out=$T/out err=$T/err
  rm -rf "$out"
  case $2 in
    off) "$RAD" -j 0 -v -s "$SHOTS" -o "$out" "$1" 2>"$err" ;;
    view) "$RAD" -j 0 -v -s "$SHOTS" --view 0 -o "$out" "$1" 2>"$err" ;;
    browser)
      "$RAD" -j 0 -v -s "$SHOTS" --view 0 -o "$out" "$1" 2>"$err" &
      pid=$!
      while ! grep -q 'view on http' "$err" 2>/dev/null && kill -0 "$pid" 2>/dev/null; do sleep 0.05; done
      watch "$(sed -n 's|^radiosity: view on \(http://[^ ]*\)$|\1|p' "$err")" "$pid"
      wait "$pid" ;;
  esac
  awk '/ shots in [0-9.]+ s/ { for (i = 1; i < NF; i++) if ($(i + 1) == "shots" && $(i + 2) == "in") { n = $i; s = $(i + 3) } }
       /^radiosity: view: / { k = $3; each = $6; max = $11; sub(/\),/, "", max); pct = $(NF - 3); sub(/%/, "", pct) }
       END { printf "%.0f %s %s %s %s\n", n / s, k == "" ? "-" : k, each == "" ? "-" : each, max == "" ? "-" : max, pct == "" ? "-" : pct }' "$err"
}

echo "| scene | elements | view | shots/s | snapshots | ms each | ms at most | share of the run |"
echo "|---|---|---|---|---|---|---|---|"
for scene in $SCENES; do
  modes="off view"
  [ "$browser" = yes ] && modes="$modes browser"
  for m in $modes; do : >"$T/$m"; done
  r=0
  while [ "$r" -lt "$REPEAT" ]; do
    for m in $modes; do run "$scene" "$m" >>"$T/$m"; done
    r=$((r + 1))
  done
  elements=$(sed -n 's/.* patches, \([0-9]*\) elements.*/\1/p' "$T/err" | tail -1)
  for m in $modes; do
    label=$m
    [ "$m" = off ] && label="without --view"
    [ "$m" = view ] && label="--view, no browser"
    [ "$m" = browser ] && label="--view, Chromium watching"
    awk -v s="$(basename "$scene")" -v e="$elements" -v l="$label" '
      { r += $1; n++; k = $2; if ($3 != "-") { each += $3; max = $4 > max ? $4 : max; pct += $5 } }
      END { if (k == "-") printf "| %s | %s | %s | %.0f | - | - | - | - |\n", s, e, l, r / n
            else printf "| %s | %s | %s | %.0f | %s | %.2f | %.2f | %.2f%% |\n", s, e, l, r / n, k, each / n, max, pct / n }' "$T/$m"
  done
done
