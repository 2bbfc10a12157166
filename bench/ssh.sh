#!/bin/bash
# make bench (part): remote workers over ssh against local ones, with the
# private sshd of tests/sshd.bash on 127.0.0.1 (so the figures are ssh's
# own cost, not a network's).
#  per shot - ms per shot and bytes per shot (protocol, and ssh's on the
#             wire as sshd counts them) with one worker: local vs over ssh
#             (Cornell box, R 256, shots 200..SHOTS of a run, after joining)
#  start    - seconds from starting the master until N workers over ssh
#             have joined (one host, slots=N), with the upload of the
#             binary and with it already there
# Rows also go to bench/results/ssh.csv. One run each, this machine only.
cd "$(dirname "$0")/.." || exit 1
RADIOSITY=$(pwd)/radiosity
export RADIOSITY
# shellcheck source=tests/lib.sh
. tests/lib.sh
# shellcheck source=tests/sshd.bash
. tests/sshd.bash
start_sshd || { echo "ssh benchmark skipped: $SSHD_WHY"; exit 0; }
trap 'stop_sshd; rm -rf "$T"' EXIT
SSH_HOME=$T/home
HOST=127.0.0.1:$SSHD_PORT
CORNELL=scenes/cornell.obj
SHOTS=1500
mkdir -p bench/results
csv=bench/results/ssh.csv

# per_shot NAME ARGS...: prints "ms_per_shot sent_per_shot received_per_shot"
# from log.csv (shots 200..SHOTS) and the -v summary line.
per_shot() {
  local name=$1; shift
  rad_ssh -v --log-every 100 -s "$SHOTS" -o "$T/$name" "$@" "$CORNELL" 2>"$T/$name.err" >/dev/null
  awk -F, 'NR > 1 && $2 >= 200 && !t0 { t0 = $1; s0 = $2 } NR > 1 { t = $1; s = $2 }
    END { printf "%.3f ", 1000 * (t - t0) / (s - s0) }' "$T/$name/log.csv"
  sed -n 's/.* \([0-9]*\) bytes\/shot sent, \([0-9]*\) received$/\1 \2/p' "$T/$name.err"
}

read -r local_ms local_tx local_rx <<<"$(per_shot local -j 1)"
echo "$HOST slots=1" >"$T/hosts-1"
# A first short run uploads the binary, so that the measured run's
# connection carries the worker's traffic only.
rad_ssh -q -s 1 -o "$T/warm" -H "$T/hosts-1" "$CORNELL" 2>/dev/null
read -r ssh_ms ssh_tx ssh_rx <<<"$(per_shot ssh -H "$T/hosts-1")"
# sshd logs each connection's totals ("Transferred: sent N, received M
# bytes"); the last is the measured run's.
wire=$(grep "Transferred:" "$T/sshd/log" | tail -1 |
  sed -n 's/.*sent \([0-9]*\), received \([0-9]*\) bytes.*/\1 \2/p')
wire_per_shot=$(echo "$wire" | awk -v n="$SHOTS" '{ printf "%.0f", ($1 + $2) / n }')

echo "Per shot, one worker, Cornell box (R 256), shots 200..$SHOTS"
echo "| worker | ms/shot | protocol bytes/shot out | in | ssh wire bytes/shot (both ways) |"
echo "|---|---|---|---|---|"
echo "| local (socket pair) | $local_ms | $local_tx | $local_rx | - |"
echo "| ssh (127.0.0.1) | $ssh_ms | $ssh_tx | $ssh_rx | $wire_per_shot |"
overhead=$(awk -v a="$local_ms" -v b="$ssh_ms" 'BEGIN { printf "%.3f ms (%+.1f%%)", b - a, 100 * (b - a) / a }')
echo "ssh overhead per shot: $overhead"

# start_time N FRESH: seconds until N ssh workers joined.
start_time() {
  local n=$1 fresh=$2 t0
  [ "$fresh" = yes ] && rm -f "$REMOTE_TMP"/radiosity-*
  echo "$HOST slots=$n" >"$T/hosts-n"
  t0=$(date +%s.%N)
  rad_ssh -v --log-every 1000000 -s 100000 -o "$T/start" -H "$T/hosts-n" "$CORNELL" 2>&1 >/dev/null |
    awk -v n="$n" -v t0="$t0" '/worker [0-9]+: joined/ && ++j == n {
      "date +%s.%N" | getline t; printf "%.2f\n", t - t0; exit }'
}
echo
echo "Start: seconds from launch until N workers over ssh joined (one host, slots=N)"
echo "| N | with upload ($(($(stat -c %s "$RADIOSITY") / 1000000)) MB) | binary already there |"
echo "|---|---|---|"
rows=""
for n in 1 2 4 8; do
  up=$(start_time "$n" yes)
  cached=$(start_time "$n" no)
  echo "| $n | $up | $cached |"
  rows="$rows$n,$up,$cached
"
done
{
  echo "measure,local,ssh"
  echo "ms_per_shot,$local_ms,$ssh_ms"
  echo "protocol_bytes_per_shot_out,$local_tx,$ssh_tx"
  echo "protocol_bytes_per_shot_in,$local_rx,$ssh_rx"
  echo "ssh_wire_bytes_per_shot,,$wire_per_shot"
  echo
  echo "workers,start_s_with_upload,start_s_cached"
  printf '%s' "$rows"
} >"$csv"
echo
echo "CSV: $csv"
