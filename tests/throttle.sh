#!/bin/bash
# A worker behind a slow link, for real: two local workers, the first
# one's output piped through `pv -L` (a rate limiter, 50 KB/s: its maze
# columns at R 128, computed in about 0.8 ms, came 20 to 65 ms apart in
# two runs, at R 256 2 ms and 31 to 56 ms; at 200 KB/s, with protocol 6's
# shorter columns, one clean-clone run had them only 2.6 times their
# computing apart and the check below failed), both in one run
# (--worker-cmd). The maze at R 128, as tests/parallel.sh runs it (half
# the time of R 256):
#  * the run converges to the -j 0 answer within 0.5% per face (as
#    tests/parallel.sh), both workers joined, none lost;
#  * the throttled worker was given work; it measured its link (its
#    columns come at least 3 times further apart than it takes to compute
#    them, as printed with -v); its queue at the end is what those
#    measurements call for (the round trip over the time between columns,
#    README, Workers); and it was given patches from below the top
#    (deferred), not the lights (those it holds while they gather more
#    power than any other may be taken back: README, Workers).
# Whether it makes the run quicker is bench/throttle.sh's business:
# timings are no pass/fail here.
#   RADIOSITY=/abs/path/radiosity bash tests/throttle.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

if ! command -v pv >/dev/null 2>&1; then
  echo "skip: pv is not installed (Debian package pv; tests/deps.sh installs it)"
  exit 77
fi

MAZE=$(cd "$(dirname "$0")/../scenes" && pwd)/maze.obj
ARGS=(-e 1e-5 -r 128)

# The first worker started is the throttled one; it leaves its pid (the
# master's child, in the worker's name) for the checks below.
cat >"$T/throttled.sh" <<EOF
#!/bin/bash
if mkdir "$T/throttled.first" 2>/dev/null; then
  echo \$\$ >"$T/throttled.pid"
  "$RADIOSITY" "\$@" | pv -q -L 50k
else
  exec "$RADIOSITY" "\$@"
fi
EOF
chmod +x "$T/throttled.sh"

run_ok_shared "maze, sequential" "$T/seq" -j 0 "${ARGS[@]}" "$MAZE" || finish
if run_ok "maze, a worker behind pv -L 50k" "$T/slow" -v -j 2 --worker-cmd "$T/throttled.sh" \
     "${ARGS[@]}" "$MAZE"; then
  check_same "throttled worker: agrees with -j 0" "$T/slow/result.csv" "$T/seq/result.csv" 0.5
  if says_times slow ": joined$" 2 && ! says slow "lost ("; then
    pass "throttled worker: both workers joined, none lost"
  else
    fail "throttled worker: joined and lost ($(grep -E 'joined|lost' "$T/slow.err" | head -3))"
  fi
  line=$(grep "(pid $(cat "$T/throttled.pid")): [0-9]* columns" "$T/slow.err")
  echo "# $line"
  # "NAME: C columns, D deferred, B taken back; queue A..B sent, E at the end, high
  # watermark up to H; X ms a column, Y ms on the wire, one every Z ms"
  read -r cols deferred back last column wire every < <(echo "$line" | awk '{
    for (i = 1; i <= NF; i++) {
      if ($(i + 1) == "columns,") c = $i
      if ($(i + 1) == "deferred,") d = $i
      if ($(i + 1) == "taken" && $(i + 2) == "back;") b = $i
      if ($(i + 1) == "at" && $(i + 2) == "the") e = $i
      if ($(i + 1) == "ms" && $(i + 2) == "a") x = $i
      if ($(i + 1) == "ms" && $(i + 3) == "the") y = $i
      if ($i == "every") z = $(i + 1) }
    print c + 0, d + 0, b + 0, e + 0, x + 0, y + 0, z + 0 }')
  if [ "$((cols + back))" -gt 0 ]; then
    pass "throttled worker: given work ($cols columns shot, $back patches taken back)"
  else fail "throttled worker: given no work ($line)"; fi
  if awk -v x="$column" -v z="$every" 'BEGIN { exit !(x > 0 && z >= 3 * x) }'; then
    pass "throttled worker: its link paces it (a column every $every ms, computed in $column ms)"
  else
    fail "throttled worker: its link not measured (a column every $every ms, computed in $column ms)"
  fi
  # Paced by its link: (column + wire + between columns) / between
  # columns, rounded up, 2..32; one either way for the printed rounding.
  want=$(awk -v x="$column" -v y="$wire" -v z="$every" 'BEGIN {
    d = (x + y + z) / z; n = int(d); if (n < d) n++
    if (n < 2) n = 2; if (n > 32) n = 32; print n }')
  if [ "$((last - want))" -ge -1 ] && [ "$((last - want))" -le 1 ]; then
    pass "throttled worker: $last sent at once at the end, as its times call for ($want)"
  else
    fail "throttled worker: $last sent at once at the end; its times call for $want"
  fi
  if [ "${deferred:-0}" -gt 0 ]; then pass "throttled worker: $deferred patches from below the top"
  else fail "throttled worker: given only the top patches (none deferred)"; fi
fi

no_workers_left "no worker process left behind"
finish
