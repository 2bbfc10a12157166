#!/bin/bash
# Stop on demand at any moment: SIGINT at random times into runs that would
# never end by themselves (-e 1e-12), through waves, division passes and
# the pictures between them, with and without workers and the pool thread.
# Every run must stop within a bound, exit 0, say so and write its results:
# a signal lost in some phase would let the run go on until this test
# kills it. (Once, in an earlier session's manual check, one run did not
# stop; 84 tries after it did.)
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
RUNS=${SIGNAL_RUNS:-12}
MODES=("-j 0" "-j 1" "-j 2" "-j 2 --pool-thread")

i=0
while [ "$i" -lt "$RUNS" ]; do
  mode=${MODES[$((i % ${#MODES[@]}))]}
  # 0 to 1.5 s after the first shot: the moment is the test's input.
  delay=$(awk -v s="$RANDOM" 'BEGIN { printf "%.3f", 1.5 * s / 32767 }')
  name=run$i
  # shellcheck disable=SC2086 # the mode's words
  bg_run "$name" $mode -e 1e-12 "$SCENES/maze.obj"
  wait_shots "$name" 1
  sleep "$delay"
  kill -INT "$PID"
  if ! wait_until 60 eval '! kill -0 "$PID" 2>/dev/null'; then
    kill -KILL "$PID" 2>/dev/null
    wait "$PID" 2>/dev/null
    fail "$mode, SIGINT $delay s after the first shot: still running ($(tail -1 "$T/$name.err"))"
    i=$((i + 1))
    continue
  fi
  wait "$PID"; rc=$?
  if [ "$rc" -eq 0 ] && grep -q "stopped on request (SIGINT)" "$T/$name.err" &&
     [ -s "$T/$name/result.csv" ]; then
    pass "$mode, SIGINT $delay s after the first shot: stopped, exit 0, results written"
  else
    fail "$mode, SIGINT $delay s after the first shot (exit $rc, $(tail -1 "$T/$name.err"))"
  fi
  i=$((i + 1))
done
finish
