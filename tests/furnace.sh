#!/bin/bash
# End-to-end furnace tests: closed boxes whose exact solution is known.
#  * a closed cube, every face Kd = rho, Ke = 1: B = Ke / (1 - rho) on every
#    face, per channel;
#  * the same with --no-overshoot agrees with the overshooting run;
#  * energy balance in a closed box of mixed materials: absorbed power
#    sum_faces area * (1 - rho)/rho * (B - Ke) equals emitted sum area * Ke;
#  * every result.csv is sane (no NaN, no negative B);
#  * a closed box with Kd = 1 has no finite solution: the program must say
#    so ("... converge ..." on stderr); on its own it stops and exits 1, and
#    stopped by the user's -s it exits 0 but still says it did not converge.
# Furnaces run at -r 64: a closed box's columns sum to 1 at any resolution,
# so the answer does not depend on it and the test stays fast.
#   RADIOSITY=/abs/path/radiosity bash tests/furnace.sh
# shellcheck source=tests/lib.sh disable=SC2046,SC2086 # word splitting of awk output and arg lists is intended
. "$(dirname "$0")/lib.sh"

EPS=1e-4        # -e for every converging run here; stated in the output

# worst_face CSV "KD_R KD_G KD_B" "KE_R KE_G KE_B": the face and channel
# whose B is furthest (relatively) from Ke/(1-Kd); prints
# "FACE CHANNEL GOT WANT".
worst_face() {
  awk -F, -v kd="$2" -v ke="$3" '
    BEGIN { split(kd, r, " "); split(ke, e, " "); split("B_r B_g B_b", nm, " ")
            for (c = 1; c <= 3; c++) w[c] = e[c] / (1 - r[c]) }
    NR > 1 { for (c = 1; c <= 3; c++) { d = ($(3 + c) - w[c]) / w[c]; if (d < 0) d = -d
             if (NR == 2 || d > worst) { worst = d; out = $1 " " nm[c] " " $(3 + c) " " w[c] } } }
    END { print out }' "$1"
}

# furnace NAME "KD" TOL [EXTRA ARGS]: uniform cube, Kd = KD, Ke = 1 1 1.
# Leaves the output directory in OUT.
furnace() {
  local name=$1 kd=$2 tol=$3 extra; shift 3
  extra="${*:+ $*}"
  OUT=$T/$name
  write_mtl "$T/$name.mtl" m "$kd" "1 1 1"
  write_box "$T/$name.obj" "$name.mtl" 1 1 1 m m m m m m
  check_inward "$name" "$T/$name.obj" 0.5 0.5 0.5 || return 1
  run_ok "furnace Kd=$kd$extra" "$OUT" -r 64 -e "$EPS" "$@" "$T/$name.obj" || return 1
  csv_sane "furnace Kd=$kd$extra" "$OUT/result.csv" 6
  set -- $(worst_face "$OUT/result.csv" "$(expand3 "$kd")" "1 1 1")
  check_rel "furnace Kd=$kd -e $EPS$extra: worst of 6 faces x 3 channels is face $1 $2 = Ke/(1-Kd) [${SECS}s]" "$3" "$4" "$tol"
}

expand3() { set -- $1; [ $# -eq 1 ] && echo "$1 $1 $1" || echo "$*"; }

# 1. Uniform furnaces.
furnace rho05 0.5 0.5
furnace rho09 0.9 0.5; OVERSHOOT09=$OUT
furnace rho099 0.99 0.5
furnace rho0999 0.999 2.5
furnace rgb "0.3 0.6 0.9" 0.5

# 2(a). --no-overshoot agrees with the overshooting run, face by face.
furnace rho09_noos 0.9 0.5 --no-overshoot
if [ -s "$OVERSHOOT09/result.csv" ] && [ -s "$T/rho09_noos/result.csv" ]; then
  set -- $(awk -F, '
    NR == FNR { if (FNR > 1) for (c = 4; c <= 6; c++) ref[$1, c] = $c; next }
    FNR > 1 { for (c = 4; c <= 6; c++) { d = ($c - ref[$1, c]) / ref[$1, c]; if (d < 0) d = -d
              if (!seen++ || d > worst) { worst = d; out = $1 " " c " " $c " " ref[$1, c] } } }
    END { print out }' "$OVERSHOOT09/result.csv" "$T/rho09_noos/result.csv")
  check_rel "furnace Kd=0.9 -e $EPS: --no-overshoot vs overshooting, worst face $1 column $2" "$3" "$4" 0.5
fi

# 2(b). Energy balance in a closed box of mixed materials. The ceiling
# (z=1) is a 3x3 grid of quads whose middle one is the light; the floor is
# Kd 0.8, wall y=0 Kd 0.2, wall x=0 coloured, the rest Kd 0.6.
E=$T/energy
write_mtl "$E.mtl" floor "0.8 0.8 0.8" "0 0 0" dark "0.2 0.2 0.2" "0 0 0" \
  colour "0.7 0.3 0.5" "0 0 0" grey "0.6 0.6 0.6" "0 0 0" light "0.5 0.5 0.5" "10 10 10"
awk 'BEGIN {
  print "mtllib energy.mtl"
  # 1..8: the cube corners, index 1 + x + 2y + 4z
  for (k = 0; k < 8; k++) printf "v %d %d %d\n", k % 2, int(k / 2) % 2, int(k / 4)
  # 9..24: the ceiling grid, vertex (i,j) = 9 + i + 4j at (i/3, j/3, 1)
  for (j = 0; j < 4; j++) for (i = 0; i < 4; i++) printf "v %.10g %.10g 1\n", i / 3, j / 3
  print "o room"
  print "usemtl floor";  print "f 1 2 4 3"
  print "usemtl dark";   print "f 1 5 6 2"
  print "usemtl grey";   print "f 3 4 8 7"
  print "usemtl colour"; print "f 1 3 7 5"
  print "usemtl grey";   print "f 2 6 8 4"
  print "o ceiling"
  for (j = 0; j < 3; j++) for (i = 0; i < 3; i++) {
    a = 9 + i + 4 * j
    print "usemtl " ((i == 1 && j == 1) ? "light" : "grey")
    print "f " a " " (a + 4) " " (a + 5) " " (a + 1)   # faces -z
  } }' >"$E.obj"
# The material of every face, in f order: "KD_R KD_G KD_B KE_R KE_G KE_B".
awk '
  FNR == NR { if ($1 == "newmtl") m = $2; if ($1 == "Kd") kd[m] = $2 " " $3 " " $4; if ($1 == "Ke") ke[m] = $2 " " $3 " " $4; next }
  $1 == "usemtl" { m = $2 } $1 == "f" { print kd[m], ke[m] }' "$E.mtl" "$E.obj" >"$E.mat"
if check_inward "energy balance" "$E.obj" 0.5 0.5 0.5 &&
   run_ok "energy balance" "$E" -e "$EPS" "$E.obj"; then
  csv_sane "energy balance" "$E/result.csv" 14
  check_rel "energy balance: total area of the 14 faces" \
    "$(awk -F, 'NR > 1 { s += $3 } END { printf "%.8g\n", s }' "$E/result.csv")" \
    "$(obj_normals "$E.obj" | awk '{ s += $7 } END { printf "%.8g\n", s }')" 1e-4
  for c in 1 2 3; do
    ch=$(echo r g b | cut -d' ' -f$c)
    set -- $(awk -F, -v c="$c" '
      NR == FNR { kd[FNR - 1] = $c; ke[FNR - 1] = $(c + 3); next }
      FNR > 1 { f = $1; emit += $3 * ke[f]; absorb += $3 * (1 - kd[f]) / kd[f] * ($(3 + c) - ke[f]) }
      END { printf "%.8g %.8g\n", absorb, emit }' FS=' ' "$E.mat" FS=, "$E/result.csv")
    check_rel "energy balance -e $EPS channel $ch: absorbed = emitted power [${SECS}s]" "$1" "$2" 1
  done
fi

# 2(d). Kd = 1 everywhere, the floor emits: no finite solution. It must be
# reported as not converging (exit 1, "converge" on stderr), never as done.
write_mtl "$T/white.mtl" white "1 1 1" "0 0 0" lamp "1 1 1" "1 1 1"
write_box "$T/white.obj" white.mtl 1 1 1 lamp white white white white white
for args in "-s 3000" ""; do
  what="closed box Kd=1 ${args:-without -s}"
  out=$T/white${args// /}
  want=1; [ -n "$args" ] && want=0  # the user's own limit is not a failure
  run_rad "$out" -r 64 $args "$T/white.obj"
  if [ "$RC" -eq "$want" ]; then pass "$what: exit status (got $RC, want $want) [${SECS}s]"
  else fail "$what: exit status (got $RC$([ "$RC" -eq 124 ] && echo " = timed out after ${LIMIT}s"), want $want)"; fi
  if grep -qi converge "$out.err"; then
    pass "$what: stderr says it did not converge (got \"$(grep -i -m1 converge "$out.err")\", want a line with 'converge')"
  else
    fail "$what: stderr says it did not converge (got \"$(head -c 200 "$out.err" | tr '\n' ' ')\", want a line with 'converge')"
  fi
  claim=$(cat "$out.out" "$out.err" | grep -i 'converged' | grep -Evi "not|n't|never|fail|diverg|cannot|unable" | head -1)
  if [ -n "$claim" ]; then fail "$what: no claim of convergence (got \"$claim\", want none)"
  else pass "$what: no claim of convergence (got none, want none)"; fi
  if [ -e "$out/result.csv" ]; then
    echo "# note: $what wrote result.csv (partial results) along with exit $RC"
    csv_sane "$what (partial)" "$out/result.csv" 6
  fi
done

finish
