#!/bin/bash
# Careless and hostile use (issue 18): nothing the run writes replaces one
# of its inputs, a link or a device; inputs that could block or are too
# large are refused at once; a closed stderr or terminal (SIGPIPE, SIGHUP)
# does not lose the results; the limits on polygons and hosts; the
# messages of careless command lines. Small runs, a few seconds in all.
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
cp "$SCENES/cornell.obj" "$SCENES/cornell.mtl" "$T/"
CB=$T/cornell.obj
QUICK=(-j 0 -r 16 -s 5 --no-subdivide)

# refused WHAT STATUS LINE ARGS...: the run exits STATUS with the one line
# LINE (a grep pattern) on stderr, quickly.
refused() {
  local what=$1 want=$2 line=$3; shift 3
  timeout 20 "$RADIOSITY" "$@" >"$T/r.out" 2>"$T/r.err"
  local rc=$? n
  n=$(wc -l <"$T/r.err")
  if [ "$rc" -eq "$want" ] && [ "$n" -eq 1 ] && grep -q -- "$line" "$T/r.err"; then
    pass "$what (got exit $rc: $(cat "$T/r.err"))"
  else
    fail "$what (got exit $rc, $n lines: $(head -3 "$T/r.err" | tr '\n' ' '); want $want, '$line')"
  fi
}

# --- 1: outputs never replace an input or a non-regular file ---------------
cp "$CB" "$T/scene-copy.obj"
refused "--checkpoint onto the scene" 2 "^radiosity: --checkpoint $CB: is the scene; refusing" \
  "${QUICK[@]}" -o "$T/o1" --checkpoint "$CB" "$CB"
refused "--checkpoint onto an MTL" 2 "is an MTL file of the scene" \
  "${QUICK[@]}" -o "$T/o1" --checkpoint "$T/cornell.mtl" "$CB"
ln "$CB" "$T/hard.obj"
refused "--checkpoint onto a hard link of the scene" 2 "is the scene ($CB)" \
  "${QUICK[@]}" -o "$T/o1" --checkpoint "$T/hard.obj" "$CB"
cmp -s "$CB" "$T/scene-copy.obj" && pass "the scene is untouched" || fail "the scene was overwritten"
mkfifo "$T/ck.fifo"
refused "--checkpoint onto a FIFO" 2 "ck.fifo: is not a regular file; refusing" \
  "${QUICK[@]}" -o "$T/o1" --checkpoint "$T/ck.fifo" "$CB"
[ -p "$T/ck.fifo" ] && pass "the FIFO is still a FIFO" || fail "the FIFO was replaced"
refused "--checkpoint onto the run's result.csv" 2 "is an output of this run (result.csv in -o" \
  "${QUICK[@]}" -o "$T/o1" --checkpoint "$T/o1/result.csv" "$CB"
run_rad "$T/ref" "${QUICK[@]}" "$CB"
cp "$T/ref/result.csv" "$T/ref-copy.csv"
refused "--reference OUT/result.csv -o OUT" 2 "result.csv: is the --reference file; refusing" \
  "${QUICK[@]}" -o "$T/ref" --reference "$T/ref/result.csv" "$CB"
refused "--converge onto the --reference" 2 "^radiosity: --converge $T/ref-copy.csv: is the --reference file" \
  "${QUICK[@]}" -o "$T/o1" --reference "$T/ref-copy.csv" --converge "$T/ref-copy.csv" "$CB"
cmp -s "$T/ref/result.csv" "$T/ref-copy.csv" && pass "the reference is untouched" \
  || fail "the reference was overwritten"
# (the resumed checkpoint may be replaced: that is how a run goes on)
run_rad "$T/ck1" "${QUICK[@]}" --checkpoint "$T/ck1.ck" "$CB"
run_rad "$T/ck1" -j 0 -r 16 -s 10 --no-subdivide --checkpoint "$T/ck1.ck" --resume "$T/ck1.ck" "$CB"
[ "$RC" -eq 0 ] && pass "--checkpoint FILE --resume FILE (exit 0)" || fail "--checkpoint FILE --resume FILE (exit $RC)"
refused "an output onto the resumed checkpoint" 2 "is the --resume checkpoint" \
  "${QUICK[@]}" -o "$T/o1" --resume "$T/ck1.ck" --converge "$T/ck1.ck" "$CB"

# --- 2: links planted where the program writes ----------------------------
echo precious >"$T/victim"
mkdir -p "$T/o2"
ln -s "$T/victim" "$T/o2/result.csv"
refused "a link planted at OUT/result.csv" 2 "o2/result.csv: is a symbolic link; refusing" \
  "${QUICK[@]}" -o "$T/o2" "$CB"
ln -s "$T/victim" "$T/o2.ck.tmp"
run_rad "$T/o3" "${QUICK[@]}" --checkpoint "$T/o2.ck" "$CB"
if [ "$RC" -eq 0 ] && [ "$(cat "$T/victim")" = precious ] && [ -s "$T/o2.ck" ]; then
  pass "a link planted at FILE.tmp is left alone (checkpoint written, target untouched)"
else
  fail "a link planted at FILE.tmp (exit $RC, target now '$(head -c 20 "$T/victim")')"
fi

# --- 7: inputs that could block or are too large ---------------------------
mkfifo "$T/scene.fifo" "$T/secret.fifo" "$T/resume.fifo"
refused "a FIFO as the scene" 2 "scene.fifo: cannot open: not a regular file" \
  "${QUICK[@]}" -o "$T/o4" "$T/scene.fifo"
refused "a FIFO as --resume" 2 "resume.fifo: not a regular file" \
  "${QUICK[@]}" -o "$T/o4" --resume "$T/resume.fifo" "$CB"
refused "a FIFO as --secret" 2 "secret.fifo: not a regular file" \
  "${QUICK[@]}" -o "$T/o4" --listen 127.0.0.1:0 --secret "$T/secret.fifo" "$CB"
sed 's/^mtllib .*/mtllib mtl.fifo/' "$CB" >"$T/fifo-mtl.obj"
mkfifo "$T/mtl.fifo"
refused "a FIFO as the mtllib" 2 "mtllib: cannot open '$T/mtl.fifo': not a regular file" \
  "${QUICK[@]}" -o "$T/o4" "$T/fifo-mtl.obj"
refused "/dev/zero as --resume" 2 "^radiosity: /dev/zero: not a regular file" \
  "${QUICK[@]}" -o "$T/o4" --resume /dev/zero "$CB"
refused "/dev/zero as --reference" 2 "^radiosity: /dev/zero: not a regular file" \
  "${QUICK[@]}" -o "$T/o4" --reference /dev/zero "$CB"
truncate -s 5G "$T/huge.ck"  # sparse: no disk used
refused "a 5 GiB --resume" 2 "huge.ck: 5368709120 bytes, more than the limit of 4 GiB" \
  "${QUICK[@]}" -o "$T/o4" --resume "$T/huge.ck" "$CB"
truncate -s 2M "$T/huge.hosts"
refused "a 2 MiB hosts file" 2 "huge.hosts: 2097152 bytes, more than the limit of 1 MiB" \
  "${QUICK[@]}" -o "$T/o4" -H "$T/huge.hosts" "$CB"

# --- 6: a closed stderr (SIGPIPE) and a closed terminal (SIGHUP) -----------
# -v writes a line per sample: the reader is gone after the first byte.
"$RADIOSITY" -v -j 0 -r 16 -s 2000 --no-subdivide -o "$T/pipe" "$SCENES/room.obj" 2>&1 | head -c1 >/dev/null
rc=${PIPESTATUS[0]}
if [ "$rc" -eq 0 ] && [ -s "$T/pipe/result.csv" ] && [ -s "$T/pipe/final.png" ]; then
  pass "stderr piped into head -c1: exit 0, results written"
else
  fail "stderr piped into head -c1 (got exit $rc, result.csv $([ -s "$T/pipe/result.csv" ] && echo written || echo missing))"
fi
bg_run hup -j 0 -r 16 -e 1e-12 --checkpoint "$T/hup.ck" "$SCENES/room.obj"
wait_shots hup 1
kill -HUP "$PID"
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && [ -s "$T/hup/result.csv" ] && [ -s "$T/hup.ck" ] &&
   grep -q "stopped on request (SIGHUP)" "$T/hup.err"; then
  pass "SIGHUP: exit 0, results and the final checkpoint written ($(tail -1 "$T/hup.err" | cut -c1-60))"
else
  fail "SIGHUP (exit $rc, $(tail -1 "$T/hup.err"))"
fi

# --- 10: amplification -----------------------------------------------------
awk 'BEGIN { n = 1001; pi = 3.14159265358979
  for (i = 0; i < n; i++) printf "v %.9f %.9f 0\n", cos(2 * pi * i / n), sin(2 * pi * i / n)
  printf "f"; for (i = 1; i <= n; i++) printf " %d", i; print "" }' >"$T/ngon.obj"
refused "a polygon of 1001 vertices" 2 "ngon.obj:1002: f: a polygon of 1001 vertices (the limit is 1000)" \
  "${QUICK[@]}" -o "$T/o5" "$T/ngon.obj"
for i in $(seq 40); do echo "localhost slots=256"; done >"$T/many.hosts"
refused "40 lines of localhost slots=256" 2 "many.hosts:17: more than 4096 slots in all" \
  "${QUICK[@]}" -o "$T/o5" -H "$T/many.hosts" "$CB"
printf 'localhost slots=200\nlocalhost slots=100\n' >"$T/local.hosts"
refused "300 local workers from the hosts file" 2 "make 300 local workers, more than 256" \
  -o "$T/o5" -H "$T/local.hosts" "$CB"

# --- 11: messages ----------------------------------------------------------
refused "--listen ''" 2 "^radiosity: --listen '': needs a name" -o "$T/o6" --listen '' --secret "$T/victim" "$CB"
refused "-o ''" 2 "^radiosity: --out '': needs a name" -o '' "$CB"
refused "--checkpoint ''" 2 "^radiosity: --checkpoint '': needs a name" --checkpoint '' "$CB"
refused "--camera ''" 2 "^radiosity: --camera '': needs a name" --camera '' "$CB"
refused "two scene names" 2 "^radiosity: one scene at a time, got 2: " "$CB" "$CB"
refused "-q with -v" 2 "^radiosity: -q and -v contradict each other" -q -v "$CB"
refused "--no-waves with --wave-fraction" 2 "--wave-fraction starts waves, and --no-waves has none" \
  --no-waves --wave-fraction 0.5 "$CB"
refused "--no-subdivide with --max-level" 2 "--max-level limits dividing, and --no-subdivide" \
  --no-subdivide --max-level 3 "$CB"
head -c 32 /dev/urandom | base64 >"$T/secret7"; chmod 700 "$T/secret7"
refused "a 0700 secret" 2 "secret7: the secret must be mode 0600 or 0400, not 0700" \
  --listen 127.0.0.1:0 --secret "$T/secret7" "$CB"
printf 'newmtl light\nKd 0\nKe 1e308 1 1\n' >"$T/hot.mtl"
sed 's/^mtllib .*/mtllib hot.mtl/; s/^usemtl .*/usemtl light/' "$CB" >"$T/hot.obj"
refused "Ke 1e308" 2 "hot.mtl:3: Ke: '1e308' is too large" "${QUICK[@]}" -o "$T/o6" "$T/hot.obj"
printf 'v 0 0 0\nv 1e200 0 0\nv 0 1e200 0\nf 1 2 3\n' >"$T/vast.obj"
refused "an area that overflows" 2 "vast.obj:4: f: face too large: its area is not a finite number" \
  "${QUICK[@]}" -o "$T/o6" "$T/vast.obj"
refused "control characters in a name" 2 $'^radiosity: [^\e]*\\\\x1b\\[31mred.obj: cannot open' \
  "${QUICK[@]}" -o "$T/o6" "$T/"$'\e[31m'"red.obj"
secret=$T/secret
head -c 32 /dev/urandom | base64 >"$secret"; chmod 600 "$secret"
timeout 20 "$RADIOSITY" -q -s 1 --listen 127.0.0.1:0 --secret "$secret" -o "$T/o7" "$CB" 2>"$T/listen.err" &
PID=$!
if wait_until 10 grep -q "listening for workers on 127.0.0.1:[1-9]" "$T/listen.err"; then
  pass "-q still prints the port --listen chose ($(head -1 "$T/listen.err"))"
else
  fail "-q hides the port --listen chose"
fi
kill "$PID" 2>/dev/null; wait "$PID" 2>/dev/null

# --- 4, 3: connect-back ------------------------------------------------------
# A peer of the handshake: "auth PORT SECRET" proves it knows the secret,
# then closes (a worker that fails at once); "hold PORT N FILE" opens N
# connections, says so in FILE and keeps them open, silent.
cat >"$T/peer.py" <<'PY'
import hashlib, hmac, os, socket, sys, time
mode, port = sys.argv[1], int(sys.argv[2])
if mode == "auth":
    key = open(sys.argv[3], "rb").read().rstrip(b" \t\r\n")
    s = socket.create_connection(("127.0.0.1", port))
    got = b""
    while len(got) < 37: got += s.recv(37 - len(got))
    mine = os.urandom(32)
    s.sendall(mine + hmac.new(key, b"radiosity worker" + got[5:] + mine, hashlib.sha256).digest())
    got = b""
    while len(got) < 32: got += s.recv(32 - len(got))
    s.close()
else:
    held = [socket.create_connection(("127.0.0.1", port)) for _ in range(int(sys.argv[3]))]
    open(sys.argv[4], "w").write("%d\n" % len(held))
    sys.stdin.read()  # until the test closes our stdin
PY
listen_port() { sed -n 's/^radiosity: listening for workers on 127.0.0.1:\([0-9]*\)$/\1/p' "$T/$1.err"; }
good_worker() { "$RADIOSITY" --worker --connect "127.0.0.1:$1" --secret "$secret" 2>"$T/good.err"; }
CONNECT=(-j 0 -r 16 -s 5 --no-subdivide --listen 127.0.0.1:0 --secret "$secret")

bg_run first "${CONNECT[@]}" "$CB"
wait_says first "listening for workers on"
port=$(listen_port first)
python3 "$T/peer.py" auth "$port" "$secret"
wait_says first "worker at 127.0.0.1:[0-9]*: "  # its failure, whatever it is
good_worker "$port"
wait "$PID"; rc=$?
if [ "$rc" -eq 0 ] && [ -s "$T/first/result.csv" ]; then
  pass "a first connect-back worker that fails: the master waits, the next one finishes the run"
else
  fail "a first connect-back worker that fails (exit $rc: $(grep -v '^wave' "$T/first.err" | tail -2 | tr '\n' ' '))"
fi

fds() { ls "/proc/$1/fd" 2>/dev/null | wc -l; }
bg_run held "${CONNECT[@]}" "$CB"
wait_says held "listening for workers on"
port=$(listen_port held)
base=$(fds "$PID")
mkfifo "$T/hold.in"
python3 "$T/peer.py" hold "$port" 60 "$T/held.n" <"$T/hold.in" &
hold=$!
exec 7>"$T/hold.in"
wait_until 20 test -s "$T/held.n"
wait_until 20 test "$(fds "$PID")" -ge $((base + 32))
n=$(fds "$PID")
exec 7>&-
wait "$hold"
good_worker "$port"
wait "$PID"; rc=$?
if [ "$n" -le $((base + 34)) ] && [ "$rc" -eq 0 ] && [ "$(grep -c refused "$T/held.err")" -le 10 ]; then
  pass "60 connections that never authenticate: $((n - base)) held at once, refusals said $(grep -c refused "$T/held.err") times, the run ends (exit 0)"
else
  fail "60 connections that never authenticate (held $((n - base)) descriptors, exit $rc, $(grep -c refused "$T/held.err") refusal lines)"
fi

# Out of descriptors: one line, a pause, and the run goes on.
mkdir -p "$T/emfile"
(ulimit -n 24; exec "$RADIOSITY" "${CONNECT[@]}" -o "$T/emfile" "$CB") >"$T/emfile.out" 2>"$T/emfile.err" &
PID=$!
wait_says emfile "listening for workers on"
port=$(listen_port emfile)
: >"$T/held.n"
python3 "$T/peer.py" hold "$port" 30 "$T/held.n" <"$T/hold.in" &
hold=$!
exec 7>"$T/hold.in"
wait_says emfile "cannot accept (Too many open files)"
exec 7>&-
wait "$hold"
good_worker "$port"
wait "$PID"; rc=$?
lines=$(wc -l <"$T/emfile.err")
if [ "$rc" -eq 0 ] && [ "$(grep -c "cannot accept" "$T/emfile.err")" -eq 1 ] && [ "$lines" -le 20 ]; then
  pass "EMFILE while accepting: said once, $lines lines in all, the run ends (exit 0)"
else
  fail "EMFILE while accepting (exit $rc, $lines lines: $(head -3 "$T/emfile.err" | tr '\n' ' '))"
fi

finish
