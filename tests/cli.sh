#!/bin/bash
# The command line end to end: outputs and formats, --reference and the RMS
# columns, bad options (exit 2, one line), an unwritable output directory
# (exit 1), and SIGINT/SIGTERM (finish the shot, write everything, exit 0;
# a second signal leaves at once).
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
CB=$SCENES/cornell.obj

# Outputs of a converged run. Sequential (-j 0) here: with workers the
# shooting order follows their timing, so only -j 0 repeats bit for bit.
run_rad "$T/cb" -j 0 -r 64 "$CB"
[ "$RC" -eq 0 ] && pass "cornell -r 64 exit 0" || fail "cornell -r 64 (got exit $RC, want 0)"
rows=$(($(wc -l <"$T/cb/result.csv") - 1))
faces=$(grep -c '^f ' "$CB")
[ "$rows" -eq "$faces" ] && pass "result.csv rows (got $rows, want $faces)" || fail "result.csv rows (got $rows, want $faces)"
csv_sane "cornell" "$T/cb/result.csv" "$faces"
head -c 8 "$T/cb/final.png" | od -An -c | grep -q 'P   N   G' && pass "final.png is a PNG" || fail "final.png is not a PNG"
hdr=$(head -1 "$T/cb/log.csv")
[ "$hdr" = "time_s,shots,wave,elements,unshot_fraction,rms,rel_rms" ] && pass "log.csv header" || fail "log.csv header (got $hdr)"
last=$(tail -1 "$T/cb/log.csv" | cut -d, -f5)
awk -v u="$last" 'BEGIN { exit !(u < 1e-3) }' && pass "last log row below epsilon (got $last)" || fail "last log row below epsilon (got $last, want < 1e-3)"
grep -q '^element vertex [1-9]' "$T/cb/result.ply" && grep -q '^property uchar red' "$T/cb/result.ply" \
  && pass "result.ply has coloured vertices" || fail "result.ply header"

# PPM output and picture size.
run_rad "$T/ppm" -r 32 -s 20 --format ppm --size 64x48 "$CB"
[ "$(head -c 2 "$T/ppm/final.ppm")" = "P6" ] && [ "$(sed -n 2p "$T/ppm/final.ppm")" = "64 48" ] \
  && pass "--format ppm --size 64x48" || fail "--format ppm --size 64x48 (header $(head -c 12 "$T/ppm/final.ppm" | tr '\n' ' '))"

# --reference: log.csv carries rms; against itself at the end it is ~0.
run_rad "$T/ref" -j 0 -r 64 --reference "$T/cb/result.csv" --log-every 50 "$CB"
first=$(sed -n 2p "$T/ref/log.csv" | cut -d, -f7)
final=$(tail -1 "$T/ref/log.csv" | cut -d, -f7)
awk -v a="$first" -v b="$final" 'BEGIN { exit !(a > 0.1 && b < 1e-6) }' \
  && pass "rel_rms falls from $first to $final against its own converged result" \
  || fail "rel_rms from $first to $final (want > 0.1 to < 1e-6)"

# The same run twice gives the same numbers (hemicube turns are seeded).
# 300 shots, through the first division passes, are enough to tell: the
# full runs take most of this test's time under the sanitizers.
run_rad "$T/once" -j 0 -r 64 -s 300 "$CB"
run_rad "$T/again" -j 0 -r 64 -s 300 "$CB"
cmp -s "$T/once/result.csv" "$T/again/result.csv" && pass "a second run gives an identical result.csv" \
  || fail "a second run differs: $(diff "$T/once/result.csv" "$T/again/result.csv" | head -3 | tr '\n' ' ')"
run_rad "$T/seed" -j 0 -r 64 -s 300 --seed 7 "$CB"
cmp -s "$T/once/result.csv" "$T/seed/result.csv" && fail "--seed 7 gives the same hemicube turns as seed 1" \
  || pass "--seed changes the hemicube turns"

# A reference of another scene is bad input.
run_rad "$T/badref" -s 5 --reference "$T/cb/result.csv" "$SCENES/maze.obj"
[ "$RC" -eq 2 ] && grep -q "^radiosity: .*result.csv:[0-9]*: " "$T/badref.err" \
  && pass "reference of another scene: exit 2, file:line ($(head -1 "$T/badref.err"))" \
  || fail "reference of another scene (exit $RC: $(head -1 "$T/badref.err"))"

# Bad options: exit 2, exactly one line starting with "radiosity: ".
bad_option() {
  local err=$T/opt.err
  timeout 20 "$RADIOSITY" "$@" >/dev/null 2>"$err"
  local rc=$? lines
  lines=$(wc -l <"$err")
  if [ "$rc" -eq 2 ] && [ "$lines" -eq 1 ] && grep -q '^radiosity: ' "$err"; then
    pass "bad option $*: $(cat "$err")"
  else
    fail "bad option $* (exit $rc, $lines lines: $(head -c 200 "$err"))"
  fi
}
bad_option -r 9 "$CB"
bad_option -r 100000 "$CB"
bad_option -r abc "$CB"
bad_option -e -1 "$CB"
bad_option -s 0 "$CB"
bad_option --size 0x10 "$CB"
bad_option --size 1000000x1000000 "$CB"
bad_option --size 16384x16384 "$CB"            # each side legal, too many pixels
bad_option --size 99999999999999999999x2 "$CB" # past long: refused, not wrapped
bad_option --patch-size 1e-4 "$CB"             # the element cap, before any allocation
bad_option --elements 65 "$CB"
bad_option --format gif "$CB"
bad_option --camera "1 2 3" "$CB"
bad_option --patch-size 0 "$CB"
bad_option --no-such-option "$CB"
bad_option -j -1 "$CB"
bad_option -j 100000 "$CB"
bad_option --queue 0 "$CB"
bad_option --timeout 0 "$CB"
bad_option --worker "$CB"
bad_option "$CB" -r
timeout 20 "$RADIOSITY" >/dev/null 2>"$T/none.err"; rc=$?
[ "$rc" -eq 2 ] && grep -q usage "$T/none.err" && pass "no scene: usage, exit 2" || fail "no scene (exit $rc)"
"$RADIOSITY" --help | grep -q -- '--reference' && pass "--help lists options" || fail "--help"
"$RADIOSITY" --version | grep -q '^radiosity [0-9]' && pass "--version" || fail "--version"

# An output directory that cannot be made is a run-time failure.
: >"$T/file"
timeout 60 "$RADIOSITY" -q -o "$T/file/sub" -s 5 "$CB" 2>"$T/unw.err"; rc=$?
[ "$rc" -eq 1 ] && grep -q "^radiosity: .*file.*: Not a directory" "$T/unw.err" \
  && pass "unwritable -o: exit 1 ($(head -1 "$T/unw.err"))" || fail "unwritable -o (exit $rc: $(head -1 "$T/unw.err"))"

# SIGINT / SIGTERM: finish the shot in hand, write everything, exit 0.
# Sent once the progress line shows shots: the handlers are in place and
# the run is under way.
for sig in INT TERM; do
  out=$T/sig$sig
  bg_run "sig$sig" -e 1e-12 "$SCENES/room.obj"
  wait_shots "sig$sig" 1
  kill -s "$sig" "$PID"
  wait "$PID"; rc=$?
  if [ "$rc" -eq 0 ] && grep -q "stopped on request" "$out.err" && [ -s "$out/result.csv" ] && [ -s "$out/final.png" ]; then
    pass "SIG$sig: exit 0, results written ($(tail -1 "$out.err"))"
  else
    fail "SIG$sig (exit $rc, $(tail -1 "$out.err"))"
  fi
done
# Under timeout(1) the run gets the signal twice, microseconds apart (to
# the program, then to its process group): one request, not two.
mkdir -p "$T/tmo"
timeout -s INT 600 "$RADIOSITY" -o "$T/tmo" -e 1e-12 "$SCENES/room.obj" >"$T/tmo.out" 2>"$T/tmo.err" &
PID=$!
wait_shots tmo 1
kill -INT "$PID"
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && grep -q "stopped on request" "$T/tmo.err" && [ -s "$T/tmo/result.csv" ]; then
  pass "SIGINT through timeout(1), twice at once: one request, exit 0, results written"
else
  fail "SIGINT through timeout(1) (exit $rc, $(tail -1 "$T/tmo.err"))"
fi
# A second signal leaves at once.
# Two signals sent back to back can merge into one pending signal, so the
# second comes once the first has stopped the run: result.csv is written,
# and the large picture after it (seconds of work) is being made.
# The directory holds an earlier run's outputs: the interrupted run must
# leave them all as they were, not some of its own beside them (its
# outputs wait in a private directory until all are written).
run_rad "$T/twice" -j 0 -r 32 -s 20 "$SCENES/cornell.obj"
cp "$T/twice/result.csv" "$T/prev-result.csv"; cp "$T/twice/log.csv" "$T/prev-log.csv"
staged() { compgen -G "$T/twice/.radiosity-*/result.csv" >/dev/null; }
bg_run twice -e 1e-12 --size 6000x6000 "$SCENES/room.obj"
wait_shots twice 1
kill -INT "$PID"
wait_run 60 staged
sleep 0.2  # a signal within 0.1 s of the first is the same request
kill -INT "$PID"
wait "$PID"; rc=$?
[ "$rc" -ne 0 ] && pass "second SIGINT ends at once (exit $rc)" || fail "second SIGINT (exit $rc, want non-zero)"
if cmp -s "$T/twice/result.csv" "$T/prev-result.csv" && cmp -s "$T/twice/log.csv" "$T/prev-log.csv" &&
   [ ! -e "$T/twice/frame-02.png" ]; then
  pass "a run ended by a second SIGINT leaves the earlier run's outputs whole"
else
  fail "a run ended by a second SIGINT mixed its outputs with the earlier run's ($(ls "$T/twice" | tr '\n' ' '))"
fi

finish
