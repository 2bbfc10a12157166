#!/bin/bash
# scenes/blender.obj, written as Blender 4.x's OBJ exporter writes (o, v/vt/vn,
# s 0 / off / 1, quads, triangles, n-gons, an MTL with Ns Ka Ks Ke Ni d
# illum), end to end: it loads without a warning, converges, every B is a
# finite number, the n-gons keep their areas, the lamp gives at least its
# Ke, and in this closed room the power absorbed equals the power emitted
# per channel (sum area (1 - Kd)/Kd (B - Ke) = sum area Ke) within 1%.
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
OBJ=$SCENES/blender.obj MTL=$SCENES/blender.mtl

run_rad "$T/bl" "$OBJ"
[ "$RC" -eq 0 ] && pass "blender.obj: exit 0 [${SECS}s]" || fail "blender.obj: exit $RC: $(head -3 "$T/bl.err")"
[ ! -s "$T/bl.err" ] && pass "blender.obj: no warning (every Blender statement accepted)" \
  || fail "blender.obj: stderr: $(head -c 300 "$T/bl.err")"
faces=$(grep -c '^f ' "$OBJ")
csv_sane "blender.obj" "$T/bl/result.csv" "$faces"
last=$(tail -1 "$T/bl/log.csv" | cut -d, -f5)
awk -v u="$last" 'BEGIN { exit !(u < 1e-3) }' && pass "converged (last unshot $last)" \
  || fail "not converged (last unshot $last, want < 1e-3)"

objects=$(awk -F, 'NR > 1 { print $2 }' "$T/bl/result.csv" | sort -u | tr '\n' ' ')
[ "$objects" = "Lamp Pedestal Room Table Wedge " ] && pass "objects from the o lines: $objects" \
  || fail "objects (got '$objects', want 'Lamp Pedestal Room Table Wedge ')"

# The octagonal lamp (radius 0.5) and the pedestal's hexagonal caps (0.35).
lamp=$(awk -F, '$2 == "Lamp" { print $3 }' "$T/bl/result.csv")
check_rel "octagon lamp area" "$lamp" "$(awk 'BEGIN { print 2 * sqrt(2) * 0.25 }')" 0.01
hexes=$(awk -F, '$2 == "Pedestal" && $3 > 0.3 && $3 < 0.34 { n++ } END { print n + 0 }' "$T/bl/result.csv")
[ "$hexes" -eq 2 ] && pass "two hexagonal caps of area 3*sqrt(3)/2 * 0.35^2" || fail "hexagonal caps: $hexes found, want 2"

# Energy: materials from the MTL, each face's from the usemtl before it.
set -- $(awk '
  FNR == 1 { file++ }
  file == 1 && $1 == "newmtl" { m = $2 }
  file == 1 && $1 == "Kd" { for (k = 1; k <= 3; k++) kd[m, k] = $(k + 1) }
  file == 1 && $1 == "Ke" { for (k = 1; k <= 3; k++) ke[m, k] = $(k + 1) }
  file == 2 && $1 == "usemtl" { cur = $2 }
  file == 2 && $1 == "f" { mat[nf++] = cur }
  file == 3 && FNR > 1 { split($0, c, ","); m = mat[c[1]]
    for (k = 1; k <= 3; k++) { b = c[3 + k]; e = ke[m, k]
      emit[k] += c[3] * e; absorb[k] += c[3] * (1 - kd[m, k]) / kd[m, k] * (b - e)
      if (b < e * (1 - 1e-6)) low++ } }
  END { for (k = 1; k <= 3; k++) printf "%.8g %.8g ", absorb[k], emit[k]; print low + 0 }' \
  "$MTL" "$OBJ" "$T/bl/result.csv")
check_rel "energy balance red: absorbed = emitted" "$1" "$2" 1
check_rel "energy balance green: absorbed = emitted" "$3" "$4" 1
check_rel "energy balance blue: absorbed = emitted" "$5" "$6" 1
[ "$7" -eq 0 ] && pass "no face below its own Ke" || fail "$7 face channels below their Ke"
awk -v e="$2" 'BEGIN { exit !(e > 1) }' && pass "the lamp emits (Ke read: emitted red power $2)" \
  || fail "no emitted power: Ke not read ($2)"

finish
