#!/bin/bash
# Start-up at scale (issue 14): rooms of N boxes (build/scenegen boxes N:
# 7 + 5N faces) started with -j J local workers; prints the load and mesh
# seconds the master prints with -v, the bytes of the scene frame each
# worker is sent, and, from the start of the master, when the first worker
# joined, when the first column was shot and when all J had joined. The
# master is killed once all have joined (what follows is not start-up),
# or after 15 minutes ("-" for what had not happened by then).
# BEFORE, if set, is another binary run side by side (same scene, back to
# back: the machine is noisy). Its frame is not printed by it: the bytes
# are those of protocol 3's layout, counted from the OBJ (a face: three
# varints, normal, area and its own vertices), marked "(v3)".
#   bash bench/startup.sh [N...]            (default 2000 20000; J: JOBS)
#   JOBS="2 4 8" BEFORE=/tmp/before2/radiosity bash bench/startup.sh 20000
# OPTS adds options to every run (e.g. OPTS=--no-groups). Then, when
# build/radiosity-startup is built, the master's start-up part by part in
# CPU seconds (load, join, estimate, mesh, groups) for each N, and for the
# Cornell box tessellated K x K and triangulated for each K in TESS
# (default none), joined and with --no-join (where groups form).
# STARTUP_BEFORE, if set, is another radiosity-startup run back to back
# on each scene: its row, and "same" or "DIFFERENT" for whether the two
# made the same mesh and groups (the hash of the mesh and of every
# group's members).
#   STARTUP_BEFORE=/tmp/before/radiosity-startup TESS=47 JOBS= bash bench/startup.sh 20000 200000
# (JOBS= skips the runs with workers.) OBJS adds scenes as they are (OBJ
# files), each joined and with --no-join, after the generated ones:
#   STARTUP_BEFORE=... OBJS=/work/scenes/cornell80t.obj JOBS= bash bench/startup.sh 200000
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
GEN=${SCENEGEN:-$PWD/build/scenegen}
[ -x "$GEN" ] || { echo "bench/startup.sh: $GEN missing: make build/scenegen" >&2; exit 1; }
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
[ $# -gt 0 ] || set -- 2000 20000
JOBS=${JOBS-2 4}
# Runs "$@" (the master), stamps its stderr lines with seconds since the
# start, and kills it when J workers have joined and a column was shot;
# prints: load mesh frame first-joined first-column all-joined.
watch() {
  J=$1; shift
  perl -MTime::HiRes=time -e '
    my ($j, @cmd) = @ARGV; my $t0 = time;
    pipe(my $r, my $w) or die; my $pid = fork;
    if (!$pid) { open(STDERR, ">&", $w); open(STDOUT, ">/dev/null"); close $r; exec @cmd; exit 127 }
    close $w;
    $SIG{ALRM} = sub { kill "KILL", $pid };  # given up: "-" for what did not come
    alarm 900;
    my ($load, $mesh, $frame, $first, $col, $all, $n) = ("-", "-", "-", "-", "-", "-", 0);
    while (my $l = <$r>) {
      my $t = sprintf "%.2f", time - $t0;
      ($load, $mesh) = ($1, $2) if $l =~ /loaded in ([0-9.]+) s, meshed in ([0-9.]+) s/;
      $frame = $1 if $l =~ /scene frame of (\d+) bytes/;
      if ($l =~ /: joined$/) { $n++; $first = $t if $n == 1; $all = $t if $n == $j }
      $col = $t if $col eq "-" && $l =~ /\s1 shots/;
      if ($all ne "-" && $col ne "-") { kill "KILL", $pid; last }
    }
    waitpid $pid, 0;
    print "$load $mesh $frame $first $col $all\n";' "$J" "$@"
}
[ -n "$JOBS" ] && printf '| binary | faces | load s | mesh s | frame bytes | bytes a face | -j | first joined s | first column s | all joined s |\n|---|---|---|---|---|---|---|---|---|---|\n'
for n in "$@"; do
  [ -n "$JOBS" ] || break
  "$GEN" boxes "$n" "$T/b.obj" >/dev/null 2>&1 || exit 1
  faces=$(grep -c '^f ' "$T/b.obj")
  # Protocol 3's scene frame: header, 82 fixed bytes, the materials, and
  # per face material, index and count varints, normal, area, vertices.
  v3=$(awk -v m="$(grep -c '^newmtl' "$T/b.mtl")" '
    function vl(x) { return x < 128 ? 1 : x < 16384 ? 2 : x < 2097152 ? 3 : 4 }
    /^f / { b += 1 + vl(i) + 1 + 32 + 24 * (NF - 1); i++ }
    END { printf "%d", 8 + 82 + vl(m + 1) + 48 * (m + 1) + vl(i) + b }' "$T/b.obj")
  for j in $JOBS; do
    for bin in ${BEFORE:+"$BEFORE"} "$RAD"; do
      read -r load mesh frame first col all < <(watch "$j" "$bin" -v --log-every 1 -j "$j" $OPTS \
        --size 16x16 -o "$T/o" "$T/b.obj")
      [ "$frame" = - ] && frame="$v3 (v3)"
      awk -v b="$bin" -v f="$faces" -v l="$load" -v m="$mesh" -v fr="$frame" -v j="$j" \
          -v a="$first" -v c="$col" -v z="$all" 'BEGIN {
        printf "| %s | %d | %s | %s | %s | %.1f | %d | %s | %s | %s |\n", b, f, l, m, fr, fr / f, j, a, c, z }'
      rm -rf "$T/o"
    done
  done
done
PARTS=${STARTUP:-$PWD/build/radiosity-startup}
[ -x "$PARTS" ] || exit 0
printf '\n| binary | scene | load s | join s | estimate s | mesh s | groups s | meshed s | faces | surfaces | elements | groups | hash |\n'
printf '|---|---|---|---|---|---|---|---|---|---|---|---|---|\n'
# parts OBJ [OPTIONS]: a row per binary; with STARTUP_BEFORE, whether
# the hashes (the last column) agree.
parts() {
  for bin in ${STARTUP_BEFORE:+"$STARTUP_BEFORE"} "$PARTS"; do
    "$bin" "$@" | sed "s|$T/||" | awk -v b="$bin ${*:2}" '{ sub(/^\| /, "| " b " | "); print }'
  done | tee "$T/rows"
  if [ -n "$STARTUP_BEFORE" ]; then
    [ "$(awk -F'|' '{ print $(NF - 1) }' "$T/rows" | sort -u | wc -l)" = 1 ] &&
      echo "| same |" || echo "| DIFFERENT |"
  fi
}
for n in "$@"; do
  "$GEN" boxes "$n" "$T/boxes$n.obj" >/dev/null 2>&1 || exit 1
  parts "$T/boxes$n.obj"
done
for k in $TESS; do
  "$GEN" tessellate scenes/cornell.obj "$k" "$T/cornell$k.obj" --tri >/dev/null 2>&1 || exit 1
  parts "$T/cornell$k.obj"
  parts "$T/cornell$k.obj" --no-join
done
for obj in $OBJS; do
  parts "$obj"
  parts "$obj" --no-join
done
