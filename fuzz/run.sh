#!/bin/sh
# Runs every fuzz target (built by `make fuzz-build` into build/fuzz/) for
# SECONDS each on its corpus, then replays fuzz/regressions/TARGET/* (inputs
# that once crashed). Prints per target: executions, executions per second,
# corpus size; a crash leaves its input in build/fuzz/artifacts/ and fails.
#   sh fuzz/run.sh SECONDS
cd "$(dirname "$0")/.." || exit 1
secs=${1:-60}
B=build/fuzz
status=0
for t in scene hosts protocol checkpoint; do
  bin=$B/${t}_fuzz
  [ -x "$bin" ] || { echo "fuzz: $bin is missing (make fuzz-build)"; exit 1; }
  mkdir -p "$B/corpus/$t" "$B/artifacts"
  log=$B/$t.log
  # The first directory takes what the run finds; the seeds are read only.
  "$bin" -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=65536 \
    -print_final_stats=1 -artifact_prefix="$B/artifacts/$t-" \
    "$B/corpus/$t" "$B/seeds/$t" >"$log" 2>&1
  rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
  rate=$(awk -v n="${execs:-0}" -v s="$secs" 'BEGIN { printf "%.0f", n / s }')
  corpus=$(ls "$B/corpus/$t" | wc -l)
  if [ $rc -ne 0 ]; then
    status=1
    echo "FAIL: fuzz $t: exit $rc after ${execs:-?} executions; the input is in $B/artifacts/"
    grep -m 5 'ERROR\|runtime error\|deadly signal' "$log"
  else
    echo "ok: fuzz $t: $execs executions in $secs s ($rate/s), corpus $corpus inputs"
  fi
  if [ -n "$(ls fuzz/regressions/$t 2>/dev/null)" ]; then
    if "$bin" fuzz/regressions/$t/* >"$log.replay" 2>&1; then
      echo "ok: fuzz $t: $(ls fuzz/regressions/$t | wc -l) regression inputs replayed"
    else
      status=1
      echo "FAIL: fuzz $t: a regression input crashes again (see $log.replay)"
    fi
  fi
done
exit $status
