#!/bin/bash
# Connect-back workers started by real cluster launchers (issue 17):
#  * Open MPI: `mpirun -np 2` starts two workers on this machine;
#  * Slurm: a one-node cluster on 127.0.0.1 that this test configures and
#    starts in its own directory (its own munged, key and socket; its own
#    slurm.conf, ports, state, spool and logs; slurmctld and slurmd), and
#    `srun -N1 -n2` starts two workers there; then the README's Slurm
#    batch script is submitted with `sbatch -n 2` as a user would.
# For mpirun and srun the master listens on 127.0.0.1:0 with a secret and
# is held (SIGSTOP) until both workers' connections are made, so that both
# join however slowly the launcher starts them (the batch script's master
# is not held: its two workers, started together by one srun, joined
# before the sixth of its 2,500 shots in every run here); then: both
# joined and none was lost, the master and the launcher exit 0, the
# answer agrees with -j 0 within 0.5% per face, and no worker process is
# left. The run is short
# (Cornell box, -r 64, half a second with two workers), undivided and
# converged to 1e-4: which elements division cuts depends on the order
# the columns come back in, and so does what is left unshot at the end;
# dividing runs at -e 1e-3 differed from -j 0 by up to 0.38% per face, an
# undivided one by 0.49% once, these by at most 0.1% on a loaded machine.
# Every daemon is stopped and every file removed at the end, whatever
# happened.
# A launcher whose package is missing (tests/deps.sh installs openmpi-bin,
# slurm-wlm and munge) or a Slurm that will not start is skipped, and then
# the test ends with 77 unless a check failed.
#   RADIOSITY=/abs/path/radiosity bash tests/launchers.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

ARGS=(-r 64 -e 1e-4 --no-subdivide)
SKIPS=0
M="" L="" JOB="" MUNGED="" CTLD="" SLURMD=""
TOP=$(cd "$(dirname "$0")/.." && pwd)
SCENE=$TOP/scenes/cornell.obj
# show NAME [N]: the last N lines of run NAME's stderr.
show() { tail -n "${2:-10}" "$T/$1.err" | sed 's/^/#   /'; }
skip_part() { echo "skip: $*"; SKIPS=$((SKIPS + 1)); }

# connected PORT: how many TCP connections to 127.0.0.1:PORT are made
# (established, seen from the connecting side; a stopped master's kernel
# still completes them into its backlog).
connected() {
  awk -v p="$(printf '0100007F:%04X' "$1")" '$3 == p && $4 == "01" { n++ } END { print n + 0 }' /proc/net/tcp
}
_two_or_gone() { [ "$(connected "$1")" -ge 2 ] || ! kill -0 "$L" 2>/dev/null; }

# launched NAME LAUNCHER...: a master into $T/NAME listening for two
# workers, LAUNCHER... followed by the worker's command line, and the
# checks.
launched() {
  local name=$1 port rc lrc; shift
  bg_run "$name" -v --listen 127.0.0.1:0 --secret "$T/secret" "${ARGS[@]}" "$SCENE"
  M=$PID
  if ! wait_says "$name" "listening for workers on"; then
    fail "$name: the master did not listen (exit status $(wait "$M"; echo $?))"; show "$name"; M=""; return
  fi
  port=$(sed -n 's/^radiosity: listening for workers on 127.0.0.1:\([0-9]*\)$/\1/p' "$T/$name.err")
  kill -STOP "$M"
  timeout "$(run_limit)" "$@" "$RADIOSITY" --worker --connect "127.0.0.1:$port" --secret "$T/secret" \
    >"$T/$name.launcher" 2>&1 &
  L=$!
  # A worker waits 10 s for the master's challenge: far more than the
  # launcher takes to start the second one.
  wait_until 60 _two_or_gone "$port"
  kill -CONT "$M"
  wait "$M"; rc=$?; M=""
  wait "$L"; lrc=$?; L=""
  if [ "$rc" -eq 0 ] && says "$name" "workers: 2 joined, 0 lost"; then
    pass "$name: 2 workers joined, none lost, master exit 0"
    check_same "$name: answer" "$T/$name/result.csv" "$T/ref/result.csv" 0.5
  else
    fail "$name: master exit $rc, $(grep -c "worker at 127.0.0.1:[0-9]*: joined" "$T/$name.err") joined (want exit 0, 2 joined and none lost)"
    show "$name"
  fi
  if [ "$lrc" -eq 0 ]; then pass "$name: the launcher exit 0"
  else fail "$name: the launcher exit $lrc (want 0)"; sed 's/^/#   /' "$T/$name.launcher" | tail -10; fi
  no_workers_left "$name: no worker process left behind"
}

# Slurm, a one-node cluster on 127.0.0.1 in $T/slurm.
# Containers have no systemd and no cgroups to delegate: processes are
# tracked by their parent pids (proctrack/linuxproc), tasks get no
# affinity or cgroup (task/none), nothing is accounted; a node that was
# down (only this one) comes back when slurmd registers.
S=$T/slurm
slurm_conf() {
  local user
  user=$(id -un)
  cat <<EOF
ClusterName=radtest
# The README's batch script takes its port from the job's number: numbered
# from 1, every run of this test would take the same one.
FirstJobId=$((RANDOM % 1000 * 1000 + RANDOM % 1000 + 1))
SlurmctldHost=localhost(127.0.0.1)
SlurmctldPort=$1
SlurmdPort=$2
SlurmUser=$user
SlurmdUser=$user
AuthType=auth/munge
AuthInfo=socket=$S/munge/socket
CredType=cred/munge
StateSaveLocation=$S/state
SlurmdSpoolDir=$S/spool
SlurmctldPidFile=$S/slurmctld.pid
SlurmdPidFile=$S/slurmd.pid
SlurmctldLogFile=$S/slurmctld.log
SlurmdLogFile=$S/slurmd.log
MailProg=/bin/true
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF
}

# Slurm's commands try for 9 s to reach a controller that is not there:
# each is bounded, and none is asked once a daemon has died.
alive() { local p; for p in "$@"; do kill -0 "$p" 2>/dev/null || return 1; done; }
node_state() { timeout 5 sinfo -h -n localhost -o %t 2>/dev/null; }
_slurm_up() { ! alive "$CTLD" "$SLURMD" || [ "$(node_state)" = idle ]; }
_no_jobs() { ! alive "$CTLD" || [ -z "$(timeout 5 squeue -h 2>&1)" ]; }

# start_slurm: munged, then slurmctld and slurmd at free ports, until the
# node is idle. Returns 1 with SLURM_WHY set when they will not come up.
start_slurm() {
  local port
  SLURM_WHY=""
  if ! { mkdir -p "$S/munge" "$S/state" "$S/spool" && chmod 700 "$S/munge" &&
         head -c 1024 /dev/urandom >"$S/munge/key" && chmod 400 "$S/munge/key"; }; then
    SLURM_WHY="cannot make $S"; return 1
  fi
  # -f: the socket's directory is private ($T), which munged warns about.
  munged -F -f --socket="$S/munge/socket" --key-file="$S/munge/key" --pid-file="$S/munge/pid" \
    --log-file="$S/munge/log" --seed-file="$S/munge/seed" 2>>"$S/munge/log" &
  MUNGED=$!
  if ! wait_until 10 test -S "$S/munge/socket"; then
    SLURM_WHY="munged would not start: $(tail -3 "$S/munge/log" | tr '\n' ' ')"; return 1
  fi
  export SLURM_CONF=$S/slurm.conf
  for _ in 1 2 3; do
    # Below the kernel's ephemeral ports, which the master's port 0 and
    # every outgoing connection take from.
    port=$((20000 + (RANDOM * 32768 + RANDOM) % 12000))
    slurm_conf "$port" $((port + 1)) >"$SLURM_CONF"
    slurmctld -D >>"$S/slurmctld.out" 2>&1 &
    CTLD=$!
    slurmd -D -N localhost >>"$S/slurmd.out" 2>&1 &
    SLURMD=$!
    wait_until 30 _slurm_up
    alive "$CTLD" "$SLURMD" && [ "$(node_state)" = idle ] && return 0
    stop_daemons "$SLURMD" "$CTLD"
    CTLD="" SLURMD=""
    SLURM_WHY="slurmctld and slurmd would not start: $(cat "$S"/*.out "$S"/*.log 2>/dev/null |
      grep -i 'error\|fatal' | grep -v 'pmix\|MPI\|state file\|backup state' | tail -3 | tr '\n' ' ')"
  done
  return 1
}

stop_daemons() {
  local p
  for p in "$@"; do [ -n "$p" ] && kill "$p" 2>/dev/null; done
  for p in "$@"; do [ -n "$p" ] && wait "$p" 2>/dev/null; done
}

# stop_slurm: once the job has left the queue (slurmd has ended its
# steps), the daemons.
stop_slurm() {
  [ -n "$CTLD" ] && wait_until 10 _no_jobs
  stop_daemons "$SLURMD" "$CTLD" "$MUNGED"
  SLURMD="" CTLD="" MUNGED=""
}

# batch_script: the README's Slurm batch script (its fenced block with
# #SBATCH lines) submitted as a user would, with `radiosity` on the PATH
# and a HOME of its own; the job and its master end with exit 0, two
# workers joined and none was lost, the answer agrees with -j 0 and no
# worker is left. The job's state is polled (sbatch --wait polls every
# few seconds).
batch_script() {
  local jid state
  mkdir -p "$T/job" "$T/home" "$T/bin"
  cp "$T/readme.sbatch" "$T/job/radiosity.sbatch"
  # A wrapper, not a link: the workers' command line names $RADIOSITY,
  # which is how no_workers_left finds them.
  printf '#!/bin/sh\nexec "%s" "$@"\n' "$RADIOSITY" >"$T/bin/radiosity"
  chmod +x "$T/bin/radiosity"
  # -n 2 and -O (a node with one processor) override the script's tasks.
  jid=$(cd "$T/job" && HOME=$T/home PATH=$T/bin:$PATH \
    sbatch --parsable -n 2 -O -o slurm.out radiosity.sbatch "$SCENE" -v "${ARGS[@]}" 2>&1) ||
    { fail "sbatch: not submitted ($jid)"; return; }
  JOB=$jid
  wait_until "$(run_limit)" _job_ended
  state=$(job_field JobState)
  JOB=""
  if [ "$state" = COMPLETED ] && [ "$(job_field ExitCode "$jid")" = 0:0 ] &&
     grep -q "workers: 2 joined, 0 lost" "$T/job/slurm.out"; then
    pass "sbatch: job $jid completed, exit 0, 2 workers joined, none lost"
    check_same "sbatch: answer" "$T/job/out-$jid/result.csv" "$T/ref/result.csv" 0.5
  else
    fail "sbatch: job $jid $state, exit $(job_field ExitCode "$jid") (want COMPLETED, 0:0, 2 workers joined, none lost)"
    tail -n 10 "$T/job/slurm.out" 2>/dev/null | sed 's/^/#   /'
  fi
  no_workers_left "sbatch: no worker process left behind"
}
# job_field FIELD [JOB]: FIELD of `scontrol show job` (the job stays
# listed for MinJobAge, 300 s, after it ends).
job_field() {
  timeout 5 scontrol -o show job "${2:-$JOB}" 2>/dev/null | tr ' ' '\n' | sed -n "s/^$1=//p"
}
_job_ended() {
  case $(job_field JobState) in PENDING|CONFIGURING|RUNNING|COMPLETING|"") return 1 ;; esac
}

# Whatever happens: the master resumed (a stopped process ignores TERM)
# and ended, the launcher ended, the cluster's daemons stopped.
cleanup() {
  [ -n "$M" ] && { kill -CONT "$M"; kill "$M"; } 2>/dev/null
  [ -n "$L" ] && kill "$L" 2>/dev/null
  [ -n "$JOB" ] && timeout 5 scancel "$JOB"
  stop_slurm
  rm -rf "$T"
}
trap cleanup EXIT

# The batch script: README.md's fenced block with #SBATCH lines, and the
# man page's example with them (roff's \- and \e read as - and \).
awk '/^```sh$/ { on = 1; b = ""; next }
     on && /^```$/ { on = 0; if (b ~ /\n#SBATCH /) printf "%s", b; next }
     on { b = b $0 "\n" }' "$TOP/README.md" >"$T/readme.sbatch"
awk '/^\.EX$/ { on = 1; b = ""; next }
     on && /^\.EE$/ { on = 0; if (b ~ /\n#SBATCH /) printf "%s", b; next }
     on { b = b $0 "\n" }' "$TOP/man/radiosity.1" | sed 's/\\-/-/g; s/\\e/\\/g' >"$T/man.sbatch"
if grep -q "^srun " "$T/readme.sbatch" && cmp -s "$T/readme.sbatch" "$T/man.sbatch"; then
  pass "README.md and the man page show one Slurm batch script ($(wc -l <"$T/readme.sbatch") lines, with srun)"
else
  fail "README.md's Slurm batch script (with srun) is the man page's (diff: $(diff "$T/readme.sbatch" "$T/man.sbatch" | head -3 | tr '\n' ' '))"
fi

run_ok "sequential reference" "$T/ref" -j 0 "${ARGS[@]}" "$SCENE" || finish
head -c 32 /dev/urandom | base64 >"$T/secret"
chmod 600 "$T/secret"

# --- Open MPI. It refuses root unless told twice; it would bind each
# worker to a core of its own, which the master needs too; and a machine
# with one core has fewer slots than workers.
if command -v mpirun >/dev/null 2>&1 && mpirun --version 2>/dev/null | grep -q "Open MPI"; then
  launched mpirun env OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 \
    mpirun -np 2 --oversubscribe --bind-to none
else
  skip_part "Open MPI: no mpirun of Open MPI (tests/deps.sh installs it; apt-get install openmpi-bin)"
fi

# --- Slurm.
missing=""
for tool in munged slurmctld slurmd srun sinfo sbatch scontrol; do
  command -v "$tool" >/dev/null 2>&1 || missing="$missing $tool"
done
if [ -n "$missing" ]; then
  skip_part "Slurm: no$missing (tests/deps.sh installs them; apt-get install slurm-wlm munge)"
elif ! start_slurm; then
  skip_part "Slurm: $SLURM_WHY"
else
  echo "# slurm: cluster radtest, node localhost idle, slurmctld port $(sed -n 's/^SlurmctldPort=//p' "$SLURM_CONF")"
  launched srun srun -N1 -n2 --overcommit
  # The script's workers connect to the name of the node it runs on.
  if getent hosts "$(hostname)" >/dev/null; then batch_script
  else skip_part "sbatch: this machine's name $(hostname) does not resolve, and the batch script's workers connect to it"; fi
fi

[ "$FAILS" -eq 0 ] && [ "$SKIPS" -gt 0 ] && { echo "$CHECKS checks, 0 failed, $SKIPS part(s) skipped"; exit 77; }
finish
