#!/bin/sh
# Runs every test: the unit tests (gtest), each end-to-end tests/*.sh on the
# real binary, and the man page lint; then the unit tests (less the long convergence runs) and a reduced set
# of end-to-end tests again on the AddressSanitizer + UndefinedBehavior-
# Sanitizer build in build/asan (any report fails the test); and the fuzz
# targets for a few seconds each (fuzz/run.sh). A shell test
# passes with exit 0, is skipped with 77 and fails otherwise. Ends with
# "N passed, N failed, N skipped".
cd "$(dirname "$0")/.." || exit 1
passed=0 failed=0 skipped=0
log=$(mktemp)
trap 'rm -f "$log" "$log".*' EXIT

# The sanitizer pass runs the end-to-end tests that reach the most code
# per second (the loader's error paths, the command line and its local
# workers, the analytic cases); the long convergence runs and the fault
# tests stay in the normal pass. A report in a worker only ends that
# worker (the master goes on without it), so the output is searched for
# reports too.
SAN_TESTS="tests/scene_input.sh tests/cli.sh tests/formfactor.sh"
# Likewise the unit tests that solve to convergence thousands of shots
# deep (about 50 s under the sanitizers) run in the normal pass only: each
# repeats the shooting loop that the shorter solver tests run too.
SAN_SKIP="Solver.ReflectingEverythingDoesNotConverge:Solver.FurnaceMatchesClosedForm"
SAN_SKIP="$SAN_SKIP:Solver.ClosedBoxAbsorbsWhatItEmits"
# and two that shoot thousands of times to compare answers (8 s there):
# the same shooting and division code runs under the shorter tests.
SAN_SKIP="$SAN_SKIP:Solver.OvershootingDoesNotChangeTheAnswer:Subdivider.SmoothLightIsNotDivided"
# and three that repeat whole runs to compare their answers (16 s there):
# the scheduler's and the queue's code runs under their shorter tests.
SAN_SKIP="$SAN_SKIP:Sim.ACrashedWorkerLosesNothing:Scheduler.LostWorkerLosesNothing"
SAN_SKIP="$SAN_SKIP:Solver.SelectIsTheFullScanOnTheShippedScenes"

# unit LABEL BINARY [GTEST FLAGS...]
# The tests run in gtest's shards, one per core, side by side: they are
# independent of each other, and one process would leave a core idle.
unit() {
  echo "== unit tests ($1)"
  label=$1 bin=$2; shift 2
  n=$(nproc 2>/dev/null || echo 1) i=0 pids=
  while [ "$i" -lt "$n" ]; do
    GTEST_TOTAL_SHARDS=$n GTEST_SHARD_INDEX=$i "$bin" --gtest_brief=1 "$@" >"$log.$i" 2>&1 &
    pids="$pids $!" i=$((i + 1))
  done
  wait $pids
  i=0
  while [ "$i" -lt "$n" ]; do
    cat "$log.$i"
    p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log.$i")
    f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log.$i")
    [ -n "$p" ] || { p=0; f=${f:-1}; echo "FAIL: unit tests ($label, shard $i) did not finish"; }
    passed=$((passed + p)) failed=$((failed + ${f:-0})) i=$((i + 1))
  done
}

# shell LABEL TESTS...: with $RADIOSITY set
shell() {
  label=$1; shift
  for t in "$@"; do
    echo "== $t ($label)"
    start=$(date +%s)
    bash "$t" >"$log" 2>&1
    rc=$?
    cat "$log"
    if [ "$label" = asan ] && grep -q 'ERROR: AddressSanitizer\|ERROR: LeakSanitizer\|runtime error:' "$log"; then
      echo "FAIL: a sanitizer report in $t"; rc=1
    fi
    secs=$(( $(date +%s) - start ))
    case $rc in
      0) passed=$((passed + 1)); echo "-- passed: $t ($label, ${secs} s)" ;;
      77) skipped=$((skipped + 1)); echo "-- skipped: $t ($label)" ;;
      *) failed=$((failed + 1)); echo "-- FAILED: $t ($label, exit $rc)" ;;
    esac
  done
}

all_shell=""
for t in tests/*.sh; do
  case "$t" in tests/run.sh|tests/deps.sh|tests/lib.sh) continue ;; esac
  all_shell="$all_shell $t"
done

RADIOSITY="$(pwd)/radiosity"
export RADIOSITY
unit build ./build/unit_tests
# shellcheck disable=SC2086 # a list of paths without spaces
shell build $all_shell

echo "== man page lint"
if out=$(groff -man -ww -z man/radiosity.1 2>&1) && [ -z "$out" ]; then
  passed=$((passed + 1))
else
  failed=$((failed + 1)); echo "FAIL: groff -man -ww -z man/radiosity.1"; echo "$out"
fi

# Each fuzz target (fuzz/) for a few seconds on its seeds, and the inputs
# that once crashed one (fuzz/regressions/) replayed. `make fuzz` runs
# them longer.
echo "== fuzz (${FUZZ_CHECK_SECONDS:-3} s per target)"
if why=$(sh fuzz/probe.sh); then
  if sh fuzz/run.sh "${FUZZ_CHECK_SECONDS:-3}"; then
    passed=$((passed + 1)); echo "-- passed: fuzz"
  else
    failed=$((failed + 1)); echo "-- FAILED: fuzz"
  fi
else
  skipped=$((skipped + 1)); echo "-- skipped: fuzz ($why)"
fi

if [ -x build/asan/radiosity ] && [ -x build/asan/unit_tests ]; then
  RADIOSITY="$(pwd)/build/asan/radiosity"
  # Leaks are reported too; abort on the first report of any kind.
  ASAN_OPTIONS=abort_on_error=1:detect_leaks=1
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
  export RADIOSITY ASAN_OPTIONS UBSAN_OPTIONS
  unit asan ./build/asan/unit_tests --gtest_filter="-$SAN_SKIP"
  # shellcheck disable=SC2086
  shell asan $SAN_TESTS
else
  skipped=$((skipped + 1)); echo "-- skipped: the sanitizer pass (no build/asan; run make asan)"
fi

echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
