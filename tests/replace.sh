#!/bin/bash
# A worker killed and replaced in the middle of a run that divides its
# mesh (issue 6: hierarchy edits survive it):
#  * the master starts one local worker A and listens for connect-back
#    workers; once the first wave has ended (the mesh is divided), worker
#    B connects: it must get the current hierarchy (the edits so far);
#  * A is killed with kill -9; B carries on alone and receives the edits
#    of the later waves as they happen;
#  * the run ends with exit 0, says A was lost, and its answer agrees with
#    the sequential run (-j 0) within 0.5% per face, so no element id went
#    astray on the way.
# The master is stopped (SIGSTOP) while B connects, so that the steps
# happen in this order however fast the machine is.
#   RADIOSITY=/abs/path/radiosity bash tests/replace.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENE="$(dirname "$0")/../scenes/cornell.obj"
# show [N]: the master's last N lines of stderr.
show() { tail -n "${1:-10}" "$T/par.err" | sed 's/^/#   /'; }
ARGS=(-r 128 -e 1e-3 --seed 3)
run_ok "sequential reference" "$T/ref" -j 0 "${ARGS[@]}" "$SCENE" || { finish; exit; }
[ "$(awk -F, 'NR > 1 { print $3 }' "$T/ref/log.csv" | sort -u | wc -l)" -ge 3 ] ||
  fail "the reference run has fewer than 3 waves: the test needs a longer run"

head -c 32 /dev/urandom | base64 >"$T/secret"
chmod 600 "$T/secret"
bg_run par -v -j 1 --listen 127.0.0.1:0 --secret "$T/secret" "${ARGS[@]}" "$SCENE"
M=$PID
if ! wait_says par "wave 1 ends"; then
  fail "the master did not end wave 1 (exit status $(wait "$M"; echo $?))"; show 10
  finish; exit
fi
kill -STOP "$M"
A=$(workers_of "$M" | head -1)
port=$(sed -n 's/^radiosity: listening for workers on 127.0.0.1:\([0-9]*\)$/\1/p' "$T/par.err")
"$RADIOSITY" --worker --connect "127.0.0.1:$port" --secret "$T/secret" 2>"$T/b.err" &
B=$!
kill -CONT "$M"
wait_says par "worker at 127.0.0.1:[0-9]*: joined" || fail "worker B did not join"
kill -9 "$A"
wait "$M"; rc=$?
wait "$B"; brc=$?

[ -n "$A" ] && [ "$rc" -eq 0 ] && [ "$brc" -eq 0 ] &&
  pass "worker A (pid $A) killed, B joined late: exit 0 (master), $brc (B)" ||
  fail "kill and replace: master exit $rc, worker B exit $brc, A pid '$A'"
says par "lost (" && pass "the master says A was lost: $(grep -m1 'lost (' "$T/par.err")" ||
  { fail "no line about the lost worker"; show; }
# The edits B received live: waves ended after A was lost.
later=$(awk '/lost \(/ { lost = 1 } lost && /wave [0-9]* ends/ { n++ } END { print n + 0 }' "$T/par.err")
[ "$later" -ge 1 ] && pass "$later wave(s) ended after A was lost: B applied their edits" ||
  { fail "no wave ended after A was lost: the test did not reach its point"; show 20; }
says par "no workers left" &&
  fail "the master fell back to computing alone: B was not working"
check_same "killed and replaced: answer" "$T/par/result.csv" "$T/ref/result.csv" 0.5
no_workers_left "no worker process left behind"
finish
