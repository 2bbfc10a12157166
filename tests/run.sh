#!/bin/sh
# Runs every test: the unit tests (gtest), each end-to-end tests/*.sh on the
# real binary, and the man page lint. A shell test passes with exit 0, is
# skipped with 77 and fails otherwise. Ends with "N passed, N failed".
cd "$(dirname "$0")/.." || exit 1
RADIOSITY="$(pwd)/radiosity"
export RADIOSITY
passed=0 failed=0 skipped=0
log=$(mktemp)
trap 'rm -f "$log"' EXIT

echo "== unit tests"
./build/unit_tests --gtest_brief=1 >"$log" 2>&1
cat "$log"
p=$(sed -n 's/^\[  PASSED  \] \([0-9]*\) test.*/\1/p' "$log")
f=$(sed -n 's/^\[  FAILED  \] \([0-9]*\) test.*/\1/p' "$log")
[ -n "$p" ] || { p=0; f=${f:-1}; echo "FAIL: unit tests did not finish"; }
passed=$((passed + p)) failed=$((failed + ${f:-0}))

for t in tests/*.sh; do
  case "$t" in tests/run.sh|tests/deps.sh|tests/lib.sh) continue ;; esac
  echo "== $t"
  start=$(date +%s)
  bash "$t"
  rc=$?
  secs=$(( $(date +%s) - start ))
  case $rc in
    0) passed=$((passed + 1)); echo "-- passed: $t (${secs} s)" ;;
    77) skipped=$((skipped + 1)); echo "-- skipped: $t" ;;
    *) failed=$((failed + 1)); echo "-- FAILED: $t (exit $rc)" ;;
  esac
done

echo "== man page lint"
if out=$(groff -man -ww -z man/radiosity.1 2>&1) && [ -z "$out" ]; then
  passed=$((passed + 1))
else
  failed=$((failed + 1)); echo "FAIL: groff -man -ww -z man/radiosity.1"; echo "$out"
fi

echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" -eq 0 ]
