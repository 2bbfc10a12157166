#!/bin/bash
# End-to-end tests of run-time subdivision and waves (on by default):
#  * smooth light is not divided: a furnace (Kd 0.9, Ke 1) still gives
#    B = Ke/(1-Kd) and log.csv's element count never changes;
#  * a sharp shadow (a small light over a square occluder over a floor)
#    is divided: more elements at the end, several waves numbered 1..N in
#    log.csv, frame-NN.png for each, and the per-face answer still agrees
#    with the undivided run's (a face's mean does not depend on how its
#    elements are cut; the per-point gain is tested in subdivide_test.cpp);
#  * the floor's vertices in result.ply crowd along the shadow's edge;
#  * the same run twice gives the same result.csv (divisions are
#    deterministic); --no-waves keeps one wave; --no-subdivide none;
#  * bad option values are refused with exit 2.
#   RADIOSITY=/abs/path/radiosity bash tests/subdivide.sh
# shellcheck source=tests/lib.sh disable=SC2046,SC2086
. "$(dirname "$0")/lib.sh"

# 1. Furnace: uniform, nothing to divide. With -j 0: the shooting order of
# parallel runs varies with timing, and on a loaded machine one order in
# dozens left a passing gradient at a division pass (2445 elements once).
write_mtl "$T/f.mtl" m "0.9 0.9 0.9" "1 1 1"
write_box "$T/f.obj" f.mtl 1 1 1 m m m m m m
if run_ok "furnace" "$T/f" -j 0 -r 64 -e 1e-4 "$T/f.obj"; then
  check_rel "furnace Kd=0.9 with subdivision: face 0 B_r = 1/(1-Kd)" "$(csv_get "$T/f/result.csv" 0 B_r)" 10 0.5
  counts=$(awk -F, 'NR > 1 { print $4 }' "$T/f/log.csv" | sort -u | tr '\n' ' ')
  waves=$(awk -F, 'NR > 1 { print $3 }' "$T/f/log.csv" | sort -u | tr '\n' ' ')
  if [ "$counts" = "2400 " ] && [ "$waves" = "1 " ]; then
    pass "furnace is not divided (got elements '$counts', waves '$waves'; want 2400, 1)"
  else
    fail "furnace is not divided (got elements '$counts', waves '$waves'; want 2400, 1)"
  fi
fi

# 2. Sharp shadow: floor z=0 (3 x 3), occluder x,y in 0.3..0.7 at z=1 (both
# sides), light 0.04 across at z=2, facing down. The shadow's edge on the
# floor is the square |x-0.5|, |y-0.5| = 0.4.
S=$T/shadow
write_mtl "$S.mtl" floor "0.6 0.6 0.6" "0 0 0" grey "0.5 0.5 0.5" "0 0 0" light "0 0 0" "100 100 100"
cat >"$S.obj" <<'EOF'
mtllib shadow.mtl
# camera 0.5 -2.2 2.6 0.5 0.5 0 45
v -1 -1 0
v 2 -1 0
v 2 2 0
v -1 2 0
v 0.3 0.3 1
v 0.7 0.3 1
v 0.7 0.7 1
v 0.3 0.7 1
v 0.3 0.3 1.001
v 0.7 0.3 1.001
v 0.7 0.7 1.001
v 0.3 0.7 1.001
v 0.48 0.48 2
v 0.52 0.48 2
v 0.52 0.52 2
v 0.48 0.52 2
o floor
usemtl floor
f 1 2 3 4
o occluder
usemtl grey
f 5 8 7 6
f 9 10 11 12
o light
usemtl light
f 13 16 15 14
EOF
args="--patch-size 0.25 -e 1e-3 $S.obj"
# -j 0: with workers the shooting order (and so the divisions) follows
# their timing; sequential runs repeat bit for bit.
run_ok "shadow" "$S/a" -j 0 $args
run_ok "shadow, again" "$S/b" -j 0 $args
run_ok "shadow --no-waves" "$S/nw" --no-waves $args
run_ok "shadow --no-subdivide" "$S/ns" --no-subdivide $args
if [ -s "$S/a/result.csv" ] && [ -s "$S/ns/result.csv" ]; then
  built=$(awk -F, 'NR == 2 { print $4 }' "$S/a/log.csv")
  final=$(awk -F, 'END { print $4 }' "$S/a/log.csv")
  nsfinal=$(awk -F, 'END { print $4 }' "$S/ns/log.csv")
  if [ "$final" -gt $((3 * built / 2)) ] && [ "$nsfinal" -eq "$built" ]; then
    pass "shadow is divided (got $built -> $final elements, --no-subdivide $nsfinal; want > 1.5x, unchanged)"
  else
    fail "shadow is divided (got $built -> $final elements, --no-subdivide $nsfinal; want > 1.5x, unchanged)"
  fi
  waves=$(awk -F, 'NR > 1 && $3 != w { printf "%s ", $3; w = $3 }' "$S/a/log.csv")
  n=$(awk -F, 'END { print $3 }' "$S/a/log.csv")
  want=$(seq 1 "$n" | tr '\n' ' ')
  if [ "$n" -ge 2 ] && [ "$waves" = "$want" ]; then
    pass "log.csv numbers the waves 1..N (got '$waves', want 2 or more in order)"
  else
    fail "log.csv numbers the waves 1..N (got '$waves', want '$want' with N >= 2)"
  fi
  frames=$(cd "$S/a" && ls frame-*.png 2>/dev/null | tr '\n' ' ')
  want=$(for i in $(seq 1 "$n"); do printf 'frame-%02d.png ' "$i"; done)
  if [ "$frames" = "$want" ]; then pass "a frame per wave (got '$frames')"
  else fail "a frame per wave (got '$frames', want '$want')"; fi
  nwwaves=$(awk -F, 'NR > 1 { print $3 }' "$S/nw/log.csv" | sort -u | tr '\n' ' ')
  nwfinal=$(awk -F, 'END { print $4 }' "$S/nw/log.csv")
  if [ "$nwwaves" = "1 " ] && [ "$nwfinal" -gt "$built" ] && [ -s "$S/nw/frame-01.png" ] && [ ! -e "$S/nw/frame-02.png" ]; then
    pass "--no-waves: one wave, still divided (got waves '$nwwaves', $nwfinal elements)"
  else
    fail "--no-waves: one wave, still divided (got waves '$nwwaves', $nwfinal elements)"
  fi
  if cmp -s "$S/a/result.csv" "$S/b/result.csv"; then pass "the same run twice gives the same result.csv"
  else fail "the same run twice gives the same result.csv (they differ)"; fi
  for f in 0 1 2; do
    check_rel "shadow face $f: B_r agrees with --no-subdivide's" \
      "$(csv_get "$S/a/result.csv" $f B_r)" "$(csv_get "$S/ns/result.csv" $f B_r)" 2
  done
  # Floor vertices per unit area within 0.1 of the shadow's edge against
  # elsewhere on the floor (result.ply: the header, then x y z r g b lines).
  set -- $(awk '
    /^element vertex/ { nv = $3 } /^end_header/ { body = 1; next }
    body && nv-- > 0 && $3 == 0 { dx = $1 - 0.5; dy = $2 - 0.5; dx = dx < 0 ? -dx : dx; dy = dy < 0 ? -dy : dy
      d = dx > dy ? dx : dy; if (d > 0.3 && d < 0.5) near++; else far++ }
    END { an = 1.0 * 1.0 - 0.6 * 0.6; printf "%.1f %.1f\n", near / an, far / (9 - an) }' "$S/a/result.ply")
  if awk -v a="$1" -v b="$2" 'BEGIN { exit !(a > 4 * b) }'; then
    pass "divisions follow the shadow's edge (got $1 floor vertices per unit area near it, $2 elsewhere; want > 4x)"
  else
    fail "divisions follow the shadow's edge (got $1 floor vertices per unit area near it, $2 elsewhere; want > 4x)"
  fi
fi

# 3. Option values.
for bad in "--subdivide-floor 0" "--subdivide-floor x" "--min-element 0" "--max-level 13" \
           "--max-level -1" "--wave-fraction 0" "--wave-fraction 2"; do
  out=$T/bad
  run_rad "$out" $bad "$S.obj"
  if [ "$RC" -eq 2 ] && grep -q "^radiosity: ${bad%% *} '" "$out.err"; then
    pass "$bad is refused (got exit $RC: $(head -1 "$out.err"))"
  else
    fail "$bad is refused (got exit $RC: $(head -1 "$out.err"); want 2 and a message naming it)"
  fi
done

finish
