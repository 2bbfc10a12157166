#!/bin/sh
# The master at a cluster's rate (issue 17), as a Markdown table on stdout.
# A real master (`radiosity -j 1 -v --no-subdivide`) is fed by
# build/radiosity-feed, a worker that answers each assignment at once with
# a real column of the scene computed in advance: the master never waits
# for a column, as with a hundred busy workers, and its own thread's
# breakdown (distributing, receiving, shooting, per shot) is what bounds
# the speedup. Its pool thread (reading, decoding, writing; pool_thread.h)
# is shown beside it, CPU per shot. The feed sleeps while it waits for
# work (--sleep): the master's two threads need this machine's two cores,
# and a feed spinning on one of them put them on one core; waking the feed
# costs the pool thread, which writes to it. FEED_SPIN=1 spins, as before. The worker's time per
# column comes from a real `-j 1` run of the same scene; max speedup is
# the one over the other. BEFORE (a radiosity binary speaking the same
# protocol) is run the same way, back to back; each figure is the run with
# the least master time of ROUNDS (default 3). Each run shoots SHOTS
# (default 10,000; -e 1e-9, so that it does not stop at convergence):
# the -v breakdown is in ms, and about 2,200 shots (the room's
# convergence) left it steps of 0.45 us a shot.
#   sh bench/feed.sh
#   BEFORE=/tmp/before/radiosity SCENES="room maze" RES="64 256" sh bench/feed.sh
cd "$(dirname "$0")/.." || exit 1
for b in radiosity build/radiosity-feed; do
  [ -x "$b" ] || { echo "bench/feed.sh: $b missing: make $b" >&2; exit 1; }
done
SCENES=${SCENES:-room maze cornell blender}
RES=${RES:-256}
ROUNDS=${ROUNDS:-3}
SHOTS=${SHOTS:-10000}
FEED="build/radiosity-feed --sleep"
[ -n "$FEED_SPIN" ] && FEED=build/radiosity-feed
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# --pool-thread for a binary that has it: the feed stands for workers on
# other machines, and -j 1 on two cores would otherwise keep the pool on
# the master's thread (UsePoolThread).
thread() { "$1" --help 2>&1 | grep -q -- --pool-thread && echo --pool-thread; }
# BIN SCENE R FEED: the breakdown of the least master time of ROUNDS runs,
# "distribute receive shoot columns worker_s pool_s" (seconds,
# counts; pool_s "-" without a pool thread).
best() {
  i=0
  while [ $i -lt "$ROUNDS" ]; do
    if [ "$4" = feed ]; then
      "$1" -v -j 1 --queue 30 --worker-cmd "$FEED" -r "$3" -s "$SHOTS" -e 1e-9 --no-subdivide $(thread "$1") \
        -o "$out/run" "scenes/$2.obj" 2>"$out/err" >/dev/null
    else
      "$1" -v -j 1 -r "$3" -s 500 --no-subdivide -o "$out/run" "scenes/$2.obj" 2>"$out/err" >/dev/null
    fi
    pool=$(sed -n 's/^radiosity: pool thread: \([0-9.]*\) s CPU.*/\1/p' "$out/err")
    sed -n 's/^radiosity: master: \([0-9.]*\) s distributing, \([0-9.]*\) s receiving, \([0-9.]*\) s shooting.* \([0-9]*\) columns in \([0-9.]*\) s.*/\1 \2 \3 \4 \5/p' "$out/err" |
      sed "s/\$/ ${pool:--}/"
    i=$((i + 1))
  done | awk '$4 > 0 { t = $1 + $2 + $3; if (!n++ || t < bt) { bt = t; b = $0 } } END { if (n) print b }'
}
echo "| scene | R | master | distribute us | receive us | shoot us | master us/shot | pool thread CPU us/shot | worker us/column | max speedup |"
echo "|---|---|---|---|---|---|---|---|---|---|"
for s in $SCENES; do
  for r in $RES; do
    w=$(best ./radiosity "$s" "$r" real)
    [ -n "$w" ] || { echo "bench/feed.sh: $s R $r: no breakdown from the -j 1 run" >&2; exit 1; }
    col=$(echo "$w" | awk '{ printf "%.0f", 1e6 * $5 / $4 }')
    for m in ${BEFORE:+before} this; do
      bin=./radiosity
      [ "$m" = before ] && bin=$BEFORE
      f=$(best "$bin" "$s" "$r" feed)
      [ -n "$f" ] || { echo "bench/feed.sh: $s R $r ($m): no breakdown; $(tail -1 "$out/err")" >&2; exit 1; }
      echo "$f" | awk -v s="$s" -v r="$r" -v m="$m" -v col="$col" '{
        n = $4; d = 1e6 * $1 / n; rc = 1e6 * $2 / n; sh = 1e6 * $3 / n; t = d + rc + sh
        pool = $6 == "-" ? "-" : sprintf("%.1f", 1e6 * $6 / n)
        printf "| %s | %s | %s | %.1f | %.1f | %.1f | %.1f | %s | %d | %.0f |\n", s, r, m, d, rc, sh, t, pool, col, col / t }'
    done
  done
done
