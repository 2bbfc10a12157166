#!/bin/bash
# A worker behind a slow link (issue 17, "Queues that set themselves"):
# does adding it make a run slower? Two tables on stdout, Markdown.
#  1. Real runs on the room (R 256): one local worker alone (-j 1), and
#     beside it one whose output goes through `pv -q -L RATE` (a rate
#     limiter; --worker-cmd), per RATE: seconds and shots to converge
#     (the defaults: epsilon 1e-3, subdivision and waves) and seconds to
#     SHOTS shots (--no-subdivide), the throttled worker's columns, the
#     patches deferred to it and taken back, its queue and the time
#     between its columns
#     (its -v line). The median of REPEAT runs each, interleaved; this
#     2-core machine is shared, so compare the rows of one table only.
#     BEFORE=other/radiosity adds its rows (no per-worker line before
#     issue 17's queues).
#  2. The same in the cluster simulation (build/radiosity-throttle: the
#     slow worker behind a link of its own at 100, 10, 1 and 0.2 Mbit/s),
#     every row charged the same fixed costs: only the link differs.
#   bash bench/throttle.sh     (RATES, default "1m 200k 50k"; SHOTS,
#                               default 1000; REPEAT, default 3)
cd "$(dirname "$0")/.." || exit 1
for b in radiosity build/radiosity-throttle; do
  [ -x "$b" ] || { echo "bench/throttle.sh: $b missing: make $b" >&2; exit 1; }
done
command -v pv >/dev/null 2>&1 || { echo "bench/throttle.sh: pv missing (apt-get install pv)" >&2; exit 1; }
RATES=${RATES:-1m 200k 50k} SHOTS=${SHOTS:-1000} REPEAT=${REPEAT:-3}
W=$(mktemp -d "${TMPDIR:-/tmp}/radiosity-throttle.XXXXXX") || exit 1
trap 'rm -rf "$W"' EXIT
# The first worker a run starts is throttled (its pid noted), the others not.
cat >"$W/throttled.sh" <<'EOF'
#!/bin/bash
if mkdir "$THROTTLE_DIR/first" 2>/dev/null; then
  echo $$ >"$THROTTLE_DIR/pid"
  "$THROTTLE_BIN" "$@" | pv -q -L "$THROTTLE_RATE"
else
  exec "$THROTTLE_BIN" "$@"
fi
EOF
chmod +x "$W/throttled.sh"

# run BIN RATE(or "") ARGS...: one run; prints "seconds shots cols deferred
# back queue every" (the last five "-" without a throttled worker's line).
run() {
  local bin=$1 rate=$2 d; shift 2
  d=$(mktemp -d "$W/run.XXXXXX")
  if [ -n "$rate" ]; then
    THROTTLE_DIR=$d THROTTLE_BIN=$bin THROTTLE_RATE=$rate \
      "$bin" -v -j 2 --worker-cmd "$W/throttled.sh" -o "$d/out" "$@" 2>"$d/err" >/dev/null
  else
    "$bin" -v -j 1 -o "$d/out" "$@" 2>"$d/err" >/dev/null
  fi
  awk -v pid="$(cat "$d/pid" 2>/dev/null)" '
    / shots in / { for (i = 1; i <= NF; i++) if ($i == "shots" && $(i + 1) == "in") { n = $(i - 1); s = $(i + 2) } }
    pid != "" && index($0, "(pid " pid "): ") {
      for (i = 1; i <= NF; i++) {
        if ($(i + 1) == "columns,") c = $i
        if ($(i + 1) == "deferred,") df = $i
        if ($(i + 1) == "taken" && $(i + 2) == "back;") tb = $i
        if ($i == "queue") q = $(i + 1)
        if ($i == "every") e = $(i + 1) } }
    END { print s, n, (c == "" ? "-" : c), (df == "" ? "-" : df), (tb == "" ? "-" : tb), (q == "" ? "-" : q), (e == "" ? "-" : e) }' "$d/err"
}

median() { sort -g | awk '{ a[NR] = $1 } END { print (NR ? a[int((NR + 1) / 2)] : "-") }'; }

echo "Real runs, the room at R 256 (\`radiosity -j 1\` alone, \`-j 2\` with one worker behind \`pv -L\`), median of $REPEAT:"
echo
echo "| program | throttled worker | s to converge | shots | s to $SHOTS shots | its columns | deferred | taken back | its queue (sent) | ms between its columns |"
echo "|---|---|---|---|---|---|---|---|---|---|"
progs="./radiosity"
[ -n "${BEFORE:-}" ] && progs="$BEFORE $progs"
for rate in "" $RATES; do
  for p in $progs; do
    : >"$W/c" && : >"$W/n"
    for _ in $(seq "$REPEAT"); do
      run "$p" "$rate" scenes/room.obj >>"$W/c"
      run "$p" "$rate" --no-subdivide -s "$SHOTS" scenes/room.obj >>"$W/n"
    done
    # The converging run nearest the median time stands for the rest.
    m=$(cut -d' ' -f1 "$W/c" | median)
    read -r _ shots cols deferred back queue every < <(awk -v m="$m" '$1 == m { print; exit }' "$W/c")
    echo "| $p | ${rate:-none (alone)} | $m | $shots | $(cut -d' ' -f1 "$W/n" | median) | $cols | $deferred | $back | $queue | $every |"
  done
done
echo
echo "The cluster simulation (\`build/radiosity-throttle\`): one worker on the 1 Gbit/s medium, alone"
echo "and beside one behind a link of its own, every row charged the same fixed costs (measured at the start):"
echo
echo "| scene | R | workers | s to converge | shots | s to $SHOTS shots | slow worker's columns | deferred | taken back | its queue (sent) | ms between its columns |"
echo "|---|---|---|---|---|---|---|---|---|---|---|"
./build/radiosity-throttle scenes/room.obj "$SHOTS" 256 1e8 1e7 1e6 2e5 || exit 1
