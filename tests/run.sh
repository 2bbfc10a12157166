#!/bin/sh
# Runs every test: the unit tests (gtest), each end-to-end tests/*.sh on the
# real binary, and the man page lint; then the unit tests (less the long convergence runs) and a reduced set
# of end-to-end tests again on the AddressSanitizer + UndefinedBehavior-
# Sanitizer build in build/asan (any report fails the test); and the fuzz
# targets for a few seconds each (fuzz/run.sh). A shell test
# passes with exit 0, is skipped with 77 and fails otherwise. Ends with
# "N passed, N failed, N skipped".
#
# The tests are independent of each other, so they run side by side, as
# many at a time as there are cores (TEST_JOBS to change it): many of them
# wait on processes, timeouts and a browser more than they compute, and
# with no more than that the ones that compute are not slowed much (the
# tests' bounds on a run, run_limit in tests/lib.sh, grow with the load).
# Each one's output is kept in a file of its own and printed whole when it
# ends, in the order they end.
cd "$(dirname "$0")/.." || exit 1
passed=0 failed=0 skipped=0
log=$(mktemp -d) || exit 1
trap 'rm -rf "$log"' EXIT
ncpu=$(nproc 2>/dev/null || echo 1)
slots=${TEST_JOBS:-$ncpu}

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

# --- the jobs; each prints its report and writes "PASSED FAILED SKIPPED"
# to the file $res.

# unit_shard LABEL BINARY INDEX TOTAL [GTEST FLAGS...]: one gtest shard.
unit_shard() {
  label=$1 bin=$2 i=$3 n=$4; shift 4
  echo "== unit tests ($label, shard $((i + 1)) of $n)"
  GTEST_TOTAL_SHARDS=$n GTEST_SHARD_INDEX=$i "$bin" --gtest_brief=1 "$@" >"$res.out" 2>&1
  rc=$?
  cat "$res.out"
  p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$res.out")
  f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$res.out")
  [ -n "$p" ] || { p=0; f=${f:-1}; echo "FAIL: unit tests ($label, shard $((i + 1))) did not finish"; }
  # Its tests passed and the process failed after them: a sanitizer's
  # report at exit (a leak), which counted as a pass before.
  if [ "$rc" -ne 0 ] && [ "${f:-0}" -eq 0 ]; then
    f=1
    echo "FAIL: unit tests ($label, shard $((i + 1))): exit status $rc after its tests passed"
  fi
  echo "$p ${f:-0} 0" >"$res"
}

# shell_test LABEL TEST: with $RADIOSITY set.
shell_test() {
  label=$1 t=$2
  echo "== $t ($label)"
  start=$(date +%s)
  bash "$t" >"$res.out" 2>&1
  rc=$?
  cat "$res.out"
  if [ "$label" = asan ] && grep -q 'ERROR: AddressSanitizer\|ERROR: LeakSanitizer\|runtime error:' "$res.out"; then
    echo "FAIL: a sanitizer report in $t"; rc=1
  fi
  secs=$(( $(date +%s) - start ))
  case $rc in
    0) echo "1 0 0" >"$res"; echo "-- passed: $t ($label, ${secs} s)" ;;
    77) echo "0 0 1" >"$res"; echo "-- skipped: $t ($label)" ;;
    *) echo "0 1 0" >"$res"; echo "-- FAILED: $t ($label, exit $rc)" ;;
  esac
}

man_lint() {
  echo "== man page lint"
  if out=$(groff -man -ww -z man/radiosity.1 2>&1) && [ -z "$out" ]; then
    echo "1 0 0" >"$res"
  else
    echo "0 1 0" >"$res"; echo "FAIL: groff -man -ww -z man/radiosity.1"; echo "$out"
  fi
}

# Each fuzz target (fuzz/) for a few seconds on its seeds, and the inputs
# that once crashed one (fuzz/regressions/) replayed. `make fuzz` runs
# them longer.
fuzz_check() {
  echo "== fuzz (${FUZZ_CHECK_SECONDS:-3} s per target)"
  if why=$(sh fuzz/probe.sh); then
    if sh fuzz/run.sh "${FUZZ_CHECK_SECONDS:-3}"; then
      echo "1 0 0" >"$res"; echo "-- passed: fuzz"
    else
      echo "0 1 0" >"$res"; echo "-- FAILED: fuzz"
    fi
  else
    echo "0 0 1" >"$res"; echo "-- skipped: fuzz ($why)"
  fi
}

# --- the pool: job CMD... starts CMD (a function above) once fewer than
# $slots jobs run; reap waits for the next job to end and prints it. A
# job says it has ended by writing its number to a pipe that the runner
# holds open for reading and writing (so a write never blocks and a read
# waits for the next line); its command runs without that descriptor.
mkfifo "$log/ended" && exec 3<>"$log/ended" || exit 1
started=0 running=0
job() {
  while [ "$running" -ge "$slots" ]; do reap; done
  started=$((started + 1))
  res=$log/$started
  ( "$@" >"$res.log" 2>&1 3>&-; echo "$started" >&3 ) &
  running=$((running + 1))
}
reap() {
  read -r j <&3
  cat "$log/$j.log"
  read -r p f s <"$log/$j" 2>/dev/null || { p=0 f=1 s=0; echo "FAIL: job $j left no result"; }
  passed=$((passed + p)) failed=$((failed + f)) skipped=$((skipped + s))
  running=$((running - 1))
}

# unit LABEL BINARY [GTEST FLAGS...]: the unit tests in two shards per
# core, so that the pool has small pieces to fill its slots with.
unit() {
  label=$1 bin=$2; shift 2
  n=$((2 * ncpu)) i=0
  while [ "$i" -lt "$n" ]; do
    job unit_shard "$label" "$bin" "$i" "$n" "$@"
    i=$((i + 1))
  done
}

all_shell=""
for t in tests/*.sh; do
  case "$t" in tests/run.sh|tests/deps.sh|tests/lib.sh) continue ;; esac
  all_shell="$all_shell $t"
done

# The longest jobs start first, so that none starts last and runs alone:
# the unit tests, then these in this order (46, 22, 15, 13, 13 and 11 s in
# a clean-clone run; only an order: every tests/*.sh runs, listed here or
# not), then the sanitizer pass and the fuzz targets (15 s), then the rest
# (6 s or less each).
LONG_TESTS="tests/parallel.sh tests/furnace.sh tests/view.sh tests/ssh.sh tests/checkpoint.sh tests/stiff.sh"
first="" rest=""
for t in $LONG_TESTS; do
  case " $all_shell " in *" $t "*) first="$first $t" ;; esac
done
for t in $all_shell; do
  case " $LONG_TESTS " in *" $t "*) ;; *) rest="$rest $t" ;; esac
done

build_env() {
  RADIOSITY="$(pwd)/radiosity"
  ASAN_OPTIONS="" UBSAN_OPTIONS=""
}
asan_env() {
  RADIOSITY="$(pwd)/build/asan/radiosity"
  # Leaks are reported too; abort on the first report of any kind.
  ASAN_OPTIONS=abort_on_error=1:detect_leaks=1
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
}
# The -j 0 runs that several tests compare against, made once for all
# of them (run_ok_shared in tests/lib.sh).
RADIOSITY_SHARED=$log/shared
mkdir "$RADIOSITY_SHARED" || exit 1
export RADIOSITY ASAN_OPTIONS UBSAN_OPTIONS RADIOSITY_SHARED
san=no
[ -x build/asan/radiosity ] && [ -x build/asan/unit_tests ] && san=yes

build_env
unit build ./build/unit_tests
for t in $first; do job shell_test build "$t"; done
if [ $san = yes ]; then
  asan_env
  unit asan ./build/asan/unit_tests --gtest_filter="-$SAN_SKIP"
  for t in $SAN_TESTS; do job shell_test asan "$t"; done
else
  skipped=$((skipped + 1)); echo "-- skipped: the sanitizer pass (no build/asan; run make asan)"
fi
build_env
job fuzz_check
for t in $rest; do job shell_test build "$t"; done
job man_lint

while [ "$running" -gt 0 ]; do reap; done

echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
