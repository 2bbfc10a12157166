#!/bin/bash
# End-to-end tests of the master with real worker processes (fork + exec
# of the binary, socketpairs, the protocol of doc/protocol.txt):
#  * -j 2 and 4 converge to the -j 0 (sequential) answer within 0.5% per
#    face (maze); so does -j 2 where shooter groups shoot (a box whose floor
#    is 12 x 12 tiles, within 1.5%: shot order moves its small tiles by the
#    hemicube's aliasing, 0.75% measured); the analytic cases hold with -j 2;
#  * kill -9 of one worker, then of every worker, mid-run: the run ends,
#    the answer is the same, stderr says what happened;
#  * -j 4 and the kill of every worker with --pool-thread (the pool on a
#    thread of its own, which this machine's two cores do not get by
#    default);
#  * SIGSTOP of a worker does not stall the run (the other worker's
#    columns keep it shooting while it is stopped); with --timeout 1 the
#    stopped worker is dropped and its patches are computed elsewhere;
#  * a worker of another protocol version, and one that sends garbage, are
#    refused with a message naming them, and the master goes on (to the
#    furnace's answer).
#   RADIOSITY=/abs/path/radiosity bash tests/parallel.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
MAZE=$SCENES/maze.obj
# The maze (four lights, corridors), converged far enough that parallel and
# sequential runs meet (0.02 to 0.09% apart measured at R 128; 0.17% at
# R 256, in twice the time), and long enough (seconds) to be hit in the
# middle by the fault tests below. Not the room: the thin sides of its
# picture frames are so under-sampled by the hemicube that a change of
# --seed alone moves them by 30%, and shot order by 0.5%.
ARGS=(-e 1e-5 -r 128)

run_ok_shared "maze, sequential" "$T/seq" -j 0 "${ARGS[@]}" "$MAZE" || finish
run_ok "maze, -j 2" "$T/j2" -j 2 -v "${ARGS[@]}" "$MAZE" &&
  check_same "maze: -j 2 agrees with -j 0" "$T/j2/result.csv" "$T/seq/result.csv" 0.5
# A frame per wave with workers too: shaded, exposed and drawn on the
# writers' thread while the next wave shoots (MasterRun::PictureLater),
# each a PNG of the default size (IHDR: 512 x 512).
if [ -s "$T/j2/log.csv" ]; then
  n=$(awk -F, 'END { print $3 }' "$T/j2/log.csv")
  frames=$(cd "$T/j2" && ls frame-*.png 2>/dev/null | tr '\n' ' ')
  want=$(for i in $(seq 1 "$n"); do printf 'frame-%02d.png ' "$i"; done)
  sizes=$(for f in "$T"/j2/frame-*.png; do od -An -tx1 -j 16 -N 8 "$f" | tr -d ' \n'; echo; done | sort -u)
  if [ "$n" -ge 2 ] && [ "$frames" = "$want" ] && [ "$sizes" = 0000020000000200 ]; then
    pass "maze, -j 2: a frame per wave, each 512x512 ($n waves)"
  else
    fail "maze, -j 2: a frame per wave (got '$frames' of sizes '$sizes', want '$want' of 512x512, 2 or more)"
  fi
fi
run_ok "maze, -j 4 --pool-thread" "$T/j4" -j 4 -v --pool-thread "${ARGS[@]}" "$MAZE" &&
  check_same "maze: -j 4 --pool-thread agrees with -j 0" "$T/j4/result.csv" "$T/seq/result.csv" 0.5
# -v names the pool thread where there is one: by default only when the
# cores leave one free beside the two local workers (UsePoolThread).
want=no; [ "$(getconf _NPROCESSORS_ONLN)" -ge 4 ] && want=yes
got=no; grep -q "^radiosity: pool thread: " "$T/j2.err" && got=yes
[ "$got" = "$want" ] && pass "-j 2 on $(getconf _NPROCESSORS_ONLN) cores: pool thread $got" ||
  fail "-j 2 on $(getconf _NPROCESSORS_ONLN) cores: pool thread (got $got, want $want)"
if grep -q "^radiosity: pool thread: [0-9.]* s CPU" "$T/j4.err"; then
  pass "-j 4 --pool-thread: $(grep "^radiosity: pool thread" "$T/j4.err")"
else
  fail "-j 4 --pool-thread: no pool thread line in -v"
fi

# Shooter groups (groups.h) on the workers as on the master: a unit box
# lit from its ceiling, the floor cut into 12 x 12 tiles that group.
awk 'BEGIN {
  print "mtllib tiles.mtl"
  print "v 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\nusemtl light\nf 1 2 3 4"
  print "v 0 0 0\nv 0 1 0\nv 0 1 1\nv 0 0 1\nusemtl wall\nf 5 6 7 8"
  print "v 1 0 0\nv 1 0 1\nv 1 1 1\nv 1 1 0\nf 9 10 11 12"
  print "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 13 14 15 16"
  print "v 0 0 1\nv 0 1 1\nv 1 1 1\nv 1 0 1\nf 17 18 19 20"
  print "usemtl floor"; v = 20
  for (i = 0; i < 12; i++) for (j = 0; j < 12; j++) {
    x = i / 12; z = j / 12; s = 1 / 12
    printf "v %.9g 0 %.9g\nv %.9g 0 %.9g\nv %.9g 0 %.9g\nv %.9g 0 %.9g\n", x, z, x, z + s, x + s, z + s, x + s, z
    printf "f %d %d %d %d\n", v + 1, v + 2, v + 3, v + 4; v += 4
  } }' >"$T/tiles.obj"
write_mtl "$T/tiles.mtl" light "0 0 0" "5 5 5" wall "0.6 0.5 0.4" "0 0 0" floor "0.5 0.5 0.5" "0 0 0"
# --no-join: joined into one surface, the tiles would be cut as one floor.
TILES=(-e 1e-5 -r 256 --patch-size 0.5 --no-join -v)
if run_ok "tiles, sequential" "$T/tseq" -j 0 "${TILES[@]}" "$T/tiles.obj" &&
   run_ok "tiles, -j 2" "$T/tj2" -j 2 "${TILES[@]}" "$T/tiles.obj"; then
  # Groups no wider than the distance to the nearest wall (groups.h).
  if grep -q " 125 shooters, 24 of them groups" "$T/tj2.err"; then
    pass "tiles: the floor shoots as 24 groups"
  else
    fail "tiles: the floor did not shoot as 24 groups ($(grep -o '[0-9]* shooters, [0-9]* of them groups' "$T/tj2.err"))"
  fi
  check_same "tiles, groups: -j 2 agrees with -j 0" "$T/tj2/result.csv" "$T/tseq/result.csv" 1.5
fi

# The C-11 case of formfactor.sh (unit squares at distance 1) with -j 2.
cat >"$T/par.mtl" <<'EOF'
newmtl light
Kd 0 0 0
Ke 1 1 1
newmtl white
Kd 1 1 1
EOF
cat >"$T/par.obj" <<'EOF'
mtllib par.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
usemtl light
f 1 2 3 4
usemtl white
f 5 8 7 6
EOF
run_ok "parallel squares, -j 2" "$T/sq" -j 2 "$T/par.obj" &&
  check_rel "parallel squares, -j 2: B = F (C-11, c = 1)" \
    "$(csv_get "$T/sq/result.csv" 1 B_r)" 0.19982490 3

# A furnace with -j 2: B = Ke / (1 - rho).
write_mtl "$T/f.mtl" m "0.9 0.9 0.9" "1 1 1"
write_box "$T/f.obj" f.mtl 1 1 1 m m m m m m
run_ok "furnace rho 0.9, -j 2" "$T/f" -j 2 -e 1e-4 -r 64 "$T/f.obj" &&
  check_rel "furnace rho 0.9, -j 2: B" "$(csv_wmean "$T/f/result.csv" B_g 0 1 2 3 4 5)" 10 0.5

LONG=("${ARGS[@]}" "$MAZE")

# Each fault below hits once both workers have joined and the master
# shoots (wait_shooting), however slow the machine.
bg_run kill1 -j 2 "${LONG[@]}"
wait_shooting kill1 2
victim=$(workers_of "$PID" | head -1)
kill -9 "$victim"
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && grep -q "lost (.*killed by signal 9" "$T/kill1.err"; then
  pass "kill -9 of one worker: exit 0, reported ($(grep -m1 lost "$T/kill1.err"))"
  check_same "kill -9 of one worker: answer" "$T/kill1/result.csv" "$T/seq/result.csv" 0.5
else
  fail "kill -9 of one worker (exit $rc; stderr: $(head -3 "$T/kill1.err"))"
fi

bg_run killall -j 2 --pool-thread "${LONG[@]}"
wait_shooting killall 2
kill -9 $(workers_of "$PID")
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && grep -q "no workers left" "$T/killall.err"; then
  pass "kill -9 of every worker (--pool-thread): the master finishes alone (exit 0)"
  check_same "kill -9 of every worker: answer" "$T/killall/result.csv" "$T/seq/result.csv" 0.5
else
  fail "kill -9 of every worker (exit $rc; stderr: $(head -3 "$T/killall.err"))"
fi

# SIGSTOP under the 10 s timeout: the other worker keeps the run going
# (log.csv rows advance while it is stopped), nothing is dropped. The
# worker stays stopped until the master has shot 100 more patches (5 rows
# of 20; more than the 10 columns a worker's queue holds at most, so the
# other worker computed them), or the wait gives up: a stalled master
# fails either here (too few rows) or by dropping the worker at 10 s.
bg_run stop -v -j 2 --log-every 20 "${LONG[@]}"
wait_shooting stop 2
victim=$(workers_of "$PID" | head -1)
kill -STOP "$victim"
from=$(shots stop); t0=$(date +%s.%N)
wait_shots stop $((from + 100))
to=$(shots stop); t1=$(date +%s.%N)
kill -CONT "$victim"
wait "$PID"; rc=$?
secs=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
rows=$(awk -F, -v a="$from" -v b="$to" 'NR > 1 && $2 > a && $2 <= b' "$T/stop/log.csv" | wc -l)
if [ "$rc" -eq 0 ] && [ "$rows" -ge 5 ] && ! grep -q "lost (" "$T/stop.err"; then
  pass "SIGSTOP of a worker for ${secs} s: no stall ($rows log rows while it was stopped), none lost"
  check_same "SIGSTOP of a worker: answer" "$T/stop/result.csv" "$T/seq/result.csv" 0.5
else
  fail "SIGSTOP of a worker (exit $rc, $rows log rows in the ${secs} s it was stopped;" \
    "$(grep -m1 "lost (" "$T/stop.err"); stderr: $(head -3 "$T/stop.err"))"
fi

# Stopped past --timeout 1: dropped, its patches computed by the other.
# It stays stopped until the master says it dropped it (or gives up).
bg_run stop2 -j 2 --timeout 1 "${LONG[@]}"
wait_shooting stop2 2
victim=$(workers_of "$PID" | head -1)
kill -STOP "$victim"
wait_says stop2 "lost (silent for"
kill -CONT "$victim" 2>/dev/null
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && grep -q "lost (silent for" "$T/stop2.err"; then
  pass "SIGSTOP past --timeout: dropped ($(grep -m1 lost "$T/stop2.err"))"
  check_same "SIGSTOP past --timeout: answer" "$T/stop2/result.csv" "$T/seq/result.csv" 0.5
else
  fail "SIGSTOP past --timeout (exit $rc; stderr: $(head -3 "$T/stop2.err"))"
fi

# A worker of protocol version 99: its hello (doc/protocol.txt) and then
# silence. With no other worker the run cannot start: exit 1.
cat >"$T/v99.sh" <<'EOF'
#!/bin/bash
# header: length 8, type 1 (hello); payload: "RADW", version 99, build "x"
printf 'RADW\143\000\001x' >"$0.payload"
printf '\010\000\000\000\001\000\000\000'
cat "$0.payload"
cat >/dev/null
EOF
chmod +x "$T/v99.sh"
run_rad "$T/v99" -j 1 --worker-cmd "$T/v99.sh" "$MAZE"
if [ "$RC" -eq 1 ] && grep -q "local worker 1 (pid [0-9]*): speaks protocol version 99, this master speaks" "$T/v99.err"; then
  pass "worker of another protocol version: refused, exit 1 ($(head -1 "$T/v99.err"))"
else
  fail "worker of another protocol version (exit $RC; stderr: $(head -3 "$T/v99.err"))"
fi

# The first worker sends garbage, the others are real: the garbage one is
# dropped with a message, the run finishes with the rest.
cat >"$T/mixed.sh" <<EOF
#!/bin/bash
if mkdir "$T/mixed.first" 2>/dev/null; then
  printf 'this is not a frame at all\n'
  cat >/dev/null
else
  exec "$RADIOSITY" "\$@"
fi
EOF
chmod +x "$T/mixed.sh"
# The garbage comes before the first shot, so the run need not be long:
# the furnace above, whose answer is known (a maze run to -e 1e-5 with the
# one real worker left took 50 s to 120 s).
run_rad "$T/mixed" -j 2 --worker-cmd "$T/mixed.sh" -e 1e-4 -r 64 "$T/f.obj"
if [ "$RC" -eq 0 ] && grep -q "sent a bad frame" "$T/mixed.err"; then
  pass "a worker sending garbage is dropped, the run goes on ($(grep -m1 'bad frame' "$T/mixed.err"))"
  check_rel "garbage worker: furnace B" "$(csv_wmean "$T/mixed/result.csv" B_g 0 1 2 3 4 5)" 10 0.5
else
  fail "a worker sending garbage (exit $RC; stderr: $(head -3 "$T/mixed.err"))"
fi

# No process may be left behind by any of the runs above.
no_workers_left "no worker process left behind"

finish
