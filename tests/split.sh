#!/bin/bash
# End-to-end test of shooter division (man page, SUBDIVISION):
#  * on the Cornell box the blocks' contact shadows split patches (more
#    patches at the end than the 628 built) by default and with --split;
#    with --no-split, 628;
#  * a checkpoint taken after splits (the run stopped by -s writes it)
#    resumes to the uninterrupted run's result.csv byte for byte (-j 0);
#  * -j 2 splits too, and its workers follow the splits: none is lost
#    (one that could not apply an edit would be), and at -j 0's shot count
#    the answer is within 5% of it per face (2.6% measured: shot order at
#    1e-2; a worker out of step would send columns of other patches).
# Furnaces and energy balance with splits on are the unit tests'
# (split_test.cpp); -j 2 against -j 0 converged is parallel.sh's maze.
#   RADIOSITY=/abs/path/radiosity bash tests/split.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

CORNELL=$(cd "$(dirname "$0")/../scenes" && pwd)/cornell.obj
ARGS=(--split -r 64 -e 1e-2)

# patches OUT: the patch count of the run's summary line (-v).
patches() { sed -n 's/^radiosity: .*; \([0-9]*\) patches, .*/\1/p' "$1.err"; }

run_ok "cornell, -j 0" "$T/whole" -v -j 0 "${ARGS[@]}" "$CORNELL" || finish
n=$(patches "$T/whole")
if [ -n "$n" ] && [ "$n" -gt 628 ]; then
  pass "cornell: patches split (got $n patches at the end, built 628)"
else
  fail "cornell: patches split (got '$n' patches at the end, want more than 628)"
fi
run_ok "cornell, default" "$T/default" -v -j 0 -s 300 -r 64 "$CORNELL" &&
  [ "$(patches "$T/default")" -gt 628 ] && pass "by default: patches split" ||
  fail "by default: patches split (got '$(patches "$T/default")', want more than 628)"
run_ok "cornell, --no-split" "$T/none" -v -j 0 -s 300 -r 64 --no-split "$CORNELL" &&
  [ "$(patches "$T/none")" = 628 ] && pass "with --no-split: the 628 patches as built" ||
  fail "with --no-split: the 628 patches as built (got '$(patches "$T/none")')"

# Stopped after the splits began, checkpointed, resumed.
total=$(awk -F, 'END { print $2 }' "$T/whole/log.csv")
half=$((total * 2 / 3))
run_ok "cornell, stopped at $half shots" "$T/part" -v -j 0 "${ARGS[@]}" -s "$half" \
  --checkpoint "$T/part.ck" "$CORNELL" || finish
k=$(patches "$T/part")
if [ -n "$k" ] && [ "$k" -gt 628 ]; then
  pass "checkpoint after splits (got $k patches at shot $half)"
else
  fail "checkpoint after splits (got '$k' patches at shot $half, want more than 628)"
fi
run_ok "cornell, resumed" "$T/resumed" -j 0 "${ARGS[@]}" --resume "$T/part.ck" "$CORNELL" &&
  if cmp -s "$T/resumed/result.csv" "$T/whole/result.csv"; then
    pass "resumed after splits: result.csv as the uninterrupted run's (cmp)"
  else
    fail "resumed after splits: result.csv as the uninterrupted run's (cmp differs)"
  fi

run_ok "cornell, -j 2" "$T/j2" -v -j 2 "${ARGS[@]}" -s "$total" "$CORNELL" &&
  check_same "cornell: -j 2 with splits near -j 0 at the same shots" "$T/j2/result.csv" \
    "$T/whole/result.csv" 5
if says j2 ": lost ("; then fail "-j 2: no worker lost (one refused an edit?)"; else pass "-j 2: no worker lost"; fi
w=$(patches "$T/j2")
[ -n "$w" ] && [ "$w" -gt 628 ] && pass "-j 2: patches split (got $w)" ||
  fail "-j 2: patches split (got '$w', want more than 628)"
finish
