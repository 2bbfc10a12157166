# shellcheck shell=bash
# Helpers shared by the end-to-end tests (tests/*.sh). Source it:
#   . "$(dirname "$0")/lib.sh"
# It checks $RADIOSITY (skip, exit 77, when unset or not executable), makes
# $T (a temporary directory removed on exit) and counts failures.
#
# Reporting: every check prints one line,
#   ok: WHAT (got X, want Y, err Z%)   or   FAIL: WHAT (got X, want Y)
# and `finish` exits 0 when nothing failed, else 1.

set -u

if [ -z "${RADIOSITY:-}" ] || [ ! -x "$RADIOSITY" ]; then
  echo "skip: set RADIOSITY to the radiosity binary (got '${RADIOSITY:-}')"
  exit 77
fi

T=$(mktemp -d "${TMPDIR:-/tmp}/radiosity-test.XXXXXX") || exit 1
trap 'rm -rf "$T"' EXIT
trap 'exit 1' INT TERM HUP

FAILS=0
CHECKS=0

fail() { echo "FAIL: $*"; FAILS=$((FAILS + 1)); CHECKS=$((CHECKS + 1)); }
pass() { echo "ok: $*"; CHECKS=$((CHECKS + 1)); }

finish() {
  echo "$CHECKS checks, $FAILS failed"
  [ "$FAILS" -eq 0 ] && exit 0
  exit 1
}

# check_rel WHAT GOT WANT TOL_PERCENT: |GOT - WANT| <= TOL% of |WANT|.
# A GOT that is not a finite number fails.
check_rel() {
  local what=$1 got=$2 want=$3 tol=$4 res
  res=$(awk -v g="$got" -v w="$want" -v t="$tol" 'BEGIN {
    if (g !~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$/) { print "bad"; exit }
    e = (g - w) / w * 100; if (e < 0) e = -e
    printf "%s %.3g\n", (e <= t ? "ok" : "fail"), e }')
  case $res in
    ok*)   pass "$what (got $got, want $want, err ${res#ok }%, tol $tol%)" ;;
    fail*) fail "$what (got $got, want $want; err ${res#fail }% > tol $tol%)" ;;
    *)     fail "$what (got '$got', want $want; not a number)" ;;
  esac
}

# run_limit: the seconds a run of the program may take before it counts
# as hung: 120 on an idle machine, times the load per core when that is
# higher (at most 10 times), so that a machine busy with other work
# (make check beside other builds) does not fail a run that only waited
# for a core. Read at each run, as the load changes.
run_limit() {
  awk -v n="$(nproc 2>/dev/null || echo 1)" '{ f = $1 / n; if (f < 1) f = 1; if (f > 10) f = 10
    printf "%d\n", 120 * f }' /proc/loadavg 2>/dev/null || echo 120
}

# run_rad OUTDIR [ARGS...]: runs the program quietly (-q unless ARGS has -v) into OUTDIR under
# `timeout $(run_limit)`; stdout/stderr go to OUTDIR.out / OUTDIR.err. Sets RC
# (exit status; 124 = timed out), LIMIT (that bound) and SECS (wall time),
# and prints the run as a comment line for the log.
run_rad() {
  local out=$1 t0 t1 quiet=-q; shift
  case " $* " in *" -v "*) quiet= ;; esac  # -v asked for: -q would contradict it
  mkdir -p "$out"
  LIMIT=$(run_limit)
  t0=$(date +%s.%N)
  timeout "$LIMIT" "$RADIOSITY" ${quiet:+"$quiet"} -o "$out" "$@" >"$out.out" 2>"$out.err"
  RC=$?
  t1=$(date +%s.%N)
  SECS=$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.1f", b - a }')
  echo "# radiosity -q -o $(basename "$out") $* -> exit $RC in ${SECS}s"
  if [ "$RC" -ne 0 ]; then
    sed 's/^/#   stderr: /' "$out.err" | head -5
  fi
  return 0
}

# bg_run NAME ARGS...: the program in the background into $T/NAME, its
# stdout and stderr in $T/NAME.out and $T/NAME.err; PID set.
bg_run() {
  local name=$1; shift
  mkdir -p "$T/$name"
  "$RADIOSITY" -o "$T/$name" "$@" >"$T/$name.out" 2>"$T/$name.err" &
  PID=$!
}

# workers_of PID: the master's local worker processes (its children).
workers_of() { pgrep -P "$1"; }

# wait_until SECS CMD...: until CMD succeeds, tried every 0.1 s for at most
# SECS seconds. The bound only catches a program that never gets there.
wait_until() {
  local i n=$(($1 * 10)); shift
  for ((i = 0; i < n; i++)); do
    "$@" && return 0
    sleep 0.1
  done
  return 1
}

# wait_run SECS CMD...: wait_until CMD succeeds or the background run $PID
# has ended (then CMD is asked once more: its last words count).
wait_run() {
  local secs=$1; shift
  wait_until "$secs" _done_or_ended "$@"
  "$@"
}
_done_or_ended() { "$@" || ! kill -0 "$PID" 2>/dev/null; }

# Every process this test starts inherits RADIOSITY_TEST=$T (the
# program's local workers too), so that the tests below see this test's
# workers only, not those of a test running beside it (tests/run.sh).
RADIOSITY_TEST=$T
export RADIOSITY_TEST

# my_workers: the pids of the worker processes of $RADIOSITY that this
# test started (their master may be gone).
my_workers() {
  local p
  for p in $(pgrep -f -- "$RADIOSITY --worker"); do
    tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qxF "RADIOSITY_TEST=$T" && echo "$p"
  done
}

# no_workers: no worker process of this test is running.
no_workers() { [ -z "$(my_workers)" ]; }

# no_workers_left WHAT: a check that no worker process of this test is
# left running (given 5 s to notice that their master is gone).
no_workers_left() {
  if wait_until 5 no_workers; then pass "$1"
  else fail "$1 (worker processes left behind: $(my_workers | tr '\n' ' '))"; fi
}

# says NAME TEXT: stderr of run NAME has TEXT (a grep pattern).
says() { grep -q -- "$2" "$T/$1.err"; }

# says_times NAME TEXT N: stderr of run NAME has N lines with TEXT.
says_times() { [ "$(grep -c -- "$2" "$T/$1.err")" -ge "$3" ]; }

# shots NAME: the last shot count run NAME printed (its progress line, or
# with -v its sample line); 0 before the first.
shots() {
  awk '/^radiosity: / { for (i = 2; i < NF; i++) if ($(i + 1) == "shots" && $i ~ /^[0-9]+$/) n = $i }
       END { print n + 0 }' "$T/$1.err"
}
has_shots() { [ "$(shots "$1")" -ge "$2" ]; }

# wait_says NAME TEXT: until says NAME TEXT, while $PID runs (at most 60 s).
wait_says() { wait_run 60 says "$1" "$2"; }

# wait_shots NAME N: until run NAME has printed N shots, while $PID runs
# (at most 60 s).
wait_shots() { wait_run 60 has_shots "$1" "$2"; }

# wait_shooting NAME N: until N workers of run NAME joined and it shoots
# (a first shot count printed): from here on a fault hits the run mid-way.
wait_shooting() { wait_run 60 says_times "$1" ": joined$" "$2" && wait_shots "$1" 1; }

# run_ok WHAT OUTDIR [ARGS...]: run_rad, and a check that it exited 0 and
# wrote result.csv. Returns 1 (after the FAIL line) when it did not.
run_ok() {
  local what=$1; shift
  run_rad "$@"
  if [ "$RC" -ne 0 ]; then
    fail "$what: exit status (got $RC, want 0)"; return 1
  fi
  if [ ! -s "$1/result.csv" ]; then
    fail "$what: result.csv written (got none, want one)"; return 1
  fi
  return 0
}

# run_ok_shared WHAT OUTDIR [ARGS...]: run_ok, for a -j 0 run that other
# tests make too (the maze converged to -e 1e-5: tests/parallel.sh,
# throttle.sh and checkpoint.sh each compare against it). Where
# tests/run.sh gives a directory for it ($RADIOSITY_SHARED), the first
# test to ask makes the run there, and the others wait for it (flock) and
# copy it into OUTDIR: -j 0 runs of one binary and arguments are the same
# bit for bit. Without it (a test run alone), run_ok.
run_ok_shared() {
  local what=$1 out=$2 dir lock; shift 2
  [ -n "${RADIOSITY_SHARED:-}" ] || { run_ok "$what" "$out" "$@"; return; }
  dir=$RADIOSITY_SHARED/$(printf '%s\n' "$RADIOSITY" "$@" | sha256sum | cut -c1-16)
  exec {lock}>"$dir.lock"
  flock "$lock"
  if [ -e "$dir.ok" ]; then
    echo "# $what: the run another test made (radiosity $*)"
  elif run_ok "$what" "$dir" "$@"; then
    : >"$dir.ok"
  else
    exec {lock}>&-; return 1
  fi
  exec {lock}>&-
  mkdir -p "$out" && cp -r "$dir/." "$out/"
}

# csv_get FILE FACE COLUMN: the value of COLUMN (header name, e.g. B_r) in
# the row whose `face` is FACE.
csv_get() {
  awk -F, -v f="$2" -v c="$3" '
    NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; next }
    k && $1 == f { print $k; exit }' "$1"
}

# csv_wmean FILE COLUMN FACE...: area-weighted mean of COLUMN over the rows
# of the given faces.
csv_wmean() {
  local file=$1 col=$2; shift 2
  awk -F, -v c="$col" -v faces="$*" '
    BEGIN { n = split(faces, a, " "); for (i = 1; i <= n; i++) want[a[i]] = 1 }
    NR == 1 { for (i = 1; i <= NF; i++) { if ($i == c) k = i; if ($i == "area") ka = i }; next }
    k && ka && ($1 in want) { s += $ka * $k; w += $ka }
    END { if (w > 0) printf "%.8g\n", s / w; else print "none" }' "$file"
}

# csv_sane WHAT FILE NFACES: header as in the contract, NFACES rows with
# face = 0..NFACES-1 in order, every area and B finite and >= 0 (no NaN).
csv_sane() {
  local what=$1 file=$2 n=$3 msg
  msg=$(awk -F, -v n="$n" '
    function num(x) { return x ~ /^[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$/ }
    NR == 1 { if ($0 != "face,object,area,B_r,B_g,B_b") { print "header is \"" $0 "\""; bad = 1; exit }; next }
    { r = NR - 2
      if ($1 != r) { print "row " NR " has face " $1 ", want " r; bad = 1; exit }
      for (i = 3; i <= 6; i++) if (!num($i) || $i + 0 < 0) {
        print "face " $1 " column " i " is \"" $i "\" (not a finite number >= 0)"; bad = 1; exit } }
    END { if (!bad && NR - 1 != n) print (NR - 1) " rows, want " n }' "$file")
  if [ -n "$msg" ]; then fail "$what: result.csv sane (got $msg)"
  else pass "$what: result.csv sane (got $n rows, finite B >= 0, want same)"; fi
}

# obj_normals FILE: one line per `f` line: "nx ny nz cx cy cz area" — the
# unit normal by Newell's method (counter-clockwise = front), the vertex
# centroid and the area. Used to check the test scenes' winding.
obj_normals() {
  awk '
    $1 == "v" { nv++; X[nv] = $2; Y[nv] = $3; Z[nv] = $4 }
    $1 == "f" { n = NF - 1
      for (i = 1; i <= n; i++) { split($(i + 1), p, "/"); id[i] = p[1] + 0; if (id[i] < 0) id[i] += nv + 1 }
      nx = ny = nz = cx = cy = cz = 0
      for (i = 1; i <= n; i++) { a = id[i]; b = id[i % n + 1]
        nx += (Y[a] - Y[b]) * (Z[a] + Z[b]); ny += (Z[a] - Z[b]) * (X[a] + X[b]); nz += (X[a] - X[b]) * (Y[a] + Y[b])
        cx += X[a] / n; cy += Y[a] / n; cz += Z[a] / n }
      l = sqrt(nx * nx + ny * ny + nz * nz)
      printf "%.6f %.6f %.6f %.9g %.9g %.9g %.9g\n", nx / l, ny / l, nz / l, cx, cy, cz, l / 2 }' "$1"
}

# write_mtl FILE NAME KD KE [NAME KD KE ...]: KD and KE are "r g b" strings.
write_mtl() {
  local file=$1; shift
  : >"$file"
  while [ $# -ge 3 ]; do
    printf 'newmtl %s\nKd %s\nKe %s\n\n' "$1" "$2" "$3" >>"$file"
    shift 3
  done
}

# write_box OBJ MTLNAME SX SY SZ M_FLOOR M_CEIL M_Y0 M_Y1 M_X0 M_X1: the
# closed box [0,SX]x[0,SY]x[0,SZ] as six quads, every one facing INWARD
# (counter-clockwise seen from inside), in this order (faces 0..5):
# floor z=0, ceiling z=SZ, wall y=0, wall y=SY, wall x=0, wall x=SX, each
# with its material. MTLNAME is the `mtllib` file name (relative to OBJ).
write_box() {
  awk -v mtl="$2" -v sx="$3" -v sy="$4" -v sz="$5" \
      -v m0="$6" -v m1="$7" -v m2="$8" -v m3="$9" -v m4="${10}" -v m5="${11}" 'BEGIN {
    print "mtllib " mtl
    # vertex k = 1 + x + 2y + 4z for the corner (x,y,z) in {0,1}^3
    for (k = 0; k < 8; k++)
      printf "v %.10g %.10g %.10g\n", (k % 2) * sx, (int(k / 2) % 2) * sy, int(k / 4) * sz
    print "o box"
    print "usemtl " m0; print "f 1 2 4 3"   # floor   z=0  -> +z
    print "usemtl " m1; print "f 5 7 8 6"   # ceiling z=SZ -> -z
    print "usemtl " m2; print "f 1 5 6 2"   # wall    y=0  -> +y
    print "usemtl " m3; print "f 3 4 8 7"   # wall    y=SY -> -y
    print "usemtl " m4; print "f 1 3 7 5"   # wall    x=0  -> +x
    print "usemtl " m5; print "f 2 6 8 4"   # wall    x=SX -> -x
  }' >"$1"
}

# check_inward WHAT OBJ CX CY CZ: every face's normal points towards the
# point (CX,CY,CZ) (a self-check of the test's own scene).
check_inward() {
  local bad
  bad=$(obj_normals "$2" | awk -v x="$3" -v y="$4" -v z="$5" '
    { if ($1 * (x - $4) + $2 * (y - $5) + $3 * (z - $6) <= 0) printf " %d", NR - 1 }')
  if [ -n "$bad" ]; then fail "$1: test scene faces inward (got outward faces:$bad, want none)"; return 1; fi
  return 0
}

# csv_diff A B: the largest per-face, per-channel difference between two
# result.csv files of one scene, relative to the face's B in B (faces
# darker than 1% of the mean B are compared against that 1%, so that
# nearly black faces do not turn noise into huge ratios). Prints
# "PERCENT FACE", or "mismatch" when the files differ in faces.
csv_diff() {
  awk -F, '
    FNR == 1 { next }
    NR == FNR { a[$1] = $4 " " $5 " " $6; next }
    { if (!($1 in a)) { bad = 1; exit }; b[$1] = $4 " " $5 " " $6; m += $4 + $5 + $6; n += 3 }
    END {
      if (bad || length(a) != length(b)) { print "mismatch"; exit }
      floor = 0.01 * m / n; worst = 0; wf = 0
      for (f in b) { split(a[f], x, " "); split(b[f], y, " ")
        for (c = 1; c <= 3; c++) { d = x[c] - y[c]; if (d < 0) d = -d
          r = d / (y[c] > floor ? y[c] : floor); if (r > worst) { worst = r; wf = f } } }
      printf "%.4f %s\n", 100 * worst, wf }' "$1" "$2"
}

# check_same WHAT A B TOL_PERCENT: csv_diff within TOL percent.
check_same() {
  local what=$1 d
  d=$(csv_diff "$2" "$3")
  case $d in
    mismatch|"") fail "$what (result.csv files differ in faces)" ;;
    *) if awk -v d="${d% *}" -v t="$4" 'BEGIN { exit !(d <= t) }'; then
         pass "$what (worst face ${d#* } differs by ${d% *}%, tol $4%)"
       else
         fail "$what (worst face ${d#* } differs by ${d% *}% > tol $4%)"
       fi ;;
  esac
}
