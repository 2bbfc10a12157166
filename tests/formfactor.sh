#!/bin/bash
# End-to-end form factors: an emitter face (Kd 0, Ke 1) and a receiver face
# (Kd 1, Ke 0) alone in the scene. The emitter reflects nothing and what
# leaves the receiver escapes, so the receiver's radiosity is exactly
#   B_r = Kd * Ke * F(receiver -> emitter) = F(receiver -> emitter),
# which is compared with the closed formulas of Howell's catalogue within
# 3 %, at the program's default settings (-q -o DIR only).
#   RADIOSITY=/abs/path/radiosity bash tests/formfactor.sh
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

TOL=3   # percent

# Closed-form view factors (awk), computed here, never hard-coded.
FF_AWK='
function atan(x) { return atan2(x, 1) }
# Howell C-11: parallel directly opposed rectangles a x b at distance c.
function c11(a, b, c,   X, Y, pi) {
  pi = atan2(0, -1); X = a / c; Y = b / c
  return 2 / (pi * X * Y) * (log(sqrt((1 + X*X) * (1 + Y*Y) / (1 + X*X + Y*Y))) \
    + X * sqrt(1 + Y*Y) * atan(X / sqrt(1 + Y*Y)) + Y * sqrt(1 + X*X) * atan(Y / sqrt(1 + X*X)) \
    - X * atan(X) - Y * atan(Y))
}
# Howell C-14: perpendicular rectangles with a common edge of length l;
# surface 1 is w wide (perpendicular to the edge), surface 2 is h high.
# Returns F(1 -> 2).
function c14(w, h, l,   W, H, S, pi, t, u, v) {
  pi = atan2(0, -1); W = w / l; H = h / l; S = H*H + W*W
  t = (1 + W*W) * (1 + H*H) / (1 + W*W + H*H)
  u = (W*W * (1 + W*W + H*H) / ((1 + W*W) * S)) ^ (W*W)
  v = (H*H * (1 + H*H + W*W) / ((1 + H*H) * S)) ^ (H*H)
  return 1 / (pi * W) * (W * atan(1 / W) + H * atan(1 / H) - sqrt(S) * atan(1 / sqrt(S)) \
    + 0.25 * log(t * u * v))
}'
ff() { awk "$FF_AWK"' BEGIN { printf "%.8g\n", '"$1"' }'; }

# Self-checks of the formulas against the catalogue's tabulated values and
# reciprocity, so that a typo here cannot pass for a program error.
check_rel "formula C-11 unit squares at distance 1 vs catalogue" "$(ff 'c11(1,1,1)')" 0.19982 0.01
check_rel "formula C-14 unit cube sides vs catalogue" "$(ff 'c14(1,1,1)')" 0.20004 0.01
for h in 1 2 0.5; do
  # A_e F(e->r) = A_r F(r->e): emitter 1x1 (w=1), receiver 1 x h.
  check_rel "formula C-14 reciprocity h=$h" "$(ff "1*c14(1,$h,1)")" "$(ff "$h*c14($h,1,1)")" 1e-6
done

write_mtl "$T/m.mtl" light "0 0 0" "1 1 1" white "1 1 1" "0 0 0"

# write_scene OBJ SCALE VERTS... FACES: VERTS is "x y z;x y z;..." (scaled
# by SCALE), FACES is "mat:i j k;mat:i j k l;..." (1-based vertex ids).
write_scene() {
  awk -v s="$2" -v vs="$3" -v fs="$4" 'BEGIN {
    print "mtllib m.mtl"
    nv = split(vs, V, ";")
    for (i = 1; i <= nv; i++) { split(V[i], c, " "); printf "v %.10g %.10g %.10g\n", c[1] * s, c[2] * s, c[3] * s }
    nf = split(fs, F, ";")
    for (i = 1; i <= nf; i++) { split(F[i], m, ":"); print "o " m[1]; print "usemtl " m[1]; print "f " m[2] }
  }' >"$1"
}

# check_normals WHAT OBJ "nx ny nz|nx ny nz|...": each face's normal.
check_normals() {
  local bad
  bad=$(obj_normals "$2" | awk -v want="$3" '
    BEGIN { split(want, W, "|") }
    { split(W[NR], w, " "); if ($1 * w[1] + $2 * w[2] + $3 * w[3] < 0.999999) printf " face %d normal (%s %s %s)", NR - 1, $1, $2, $3 }')
  if [ -n "$bad" ]; then fail "$1: test scene winding (got$bad, want $3)"; return 1; fi
  return 0
}

# run_case WHAT OBJ NFACES "RECEIVER FACES" WANT [EMITTER FACES]: runs at
# default settings and compares the area-weighted mean B_r of the receiver
# faces with WANT; the emitter faces must show B = Ke = 1.
run_case() {
  local what=$1 obj=$2 n=$3 recv=$4 want=$5 emit=${6:-0} out got
  out=$T/$(basename "$obj" .obj)
  run_ok "$what" "$out" "$obj" || return
  csv_sane "$what" "$out/result.csv" "$n"
  # shellcheck disable=SC2086 # face lists split on purpose
  got=$(csv_wmean "$out/result.csv" B_r $recv)
  check_rel "$what: receiver B_r = F(receiver->emitter) [${SECS}s]" "$got" "$want" "$TOL"
  # shellcheck disable=SC2086
  got=$(csv_wmean "$out/result.csv" B_r $emit)
  check_rel "$what: emitter B_r = Ke" "$got" 1 "$TOL"
}

SQUARE_E="0 0 0;1 0 0;1 1 0;0 1 0"     # z=0, faces +z: vertices 1-4

# 1. Parallel unit squares directly opposed (C-11).
for c in 0.25 1 4; do
  obj=$T/par_$c.obj
  write_scene "$obj" 1 "$SQUARE_E;0 0 $c;1 0 $c;1 1 $c;0 1 $c" "light:1 2 3 4;white:5 8 7 6"
  check_normals "parallel c=$c" "$obj" "0 0 1|0 0 -1" || continue
  run_case "parallel unit squares c=$c" "$obj" 2 1 "$(ff "c11(1,1,$c)")"
done

# 2. Perpendicular rectangles with a common edge (C-14): emitter 1x1 in the
# plane y=0 facing +y, receiver [0,1]x[0,h] in the plane z=0 facing +z; the
# common edge is the x axis, l=1. Receiver = surface 1 (w=h), emitter =
# surface 2 (height 1): F(r->e) = c14(h, 1, 1).
for h in 1 2; do
  obj=$T/perp_$h.obj
  write_scene "$obj" 1 "0 0 0;0 0 1;1 0 1;1 0 0;0 $h 0;1 $h 0" "light:1 2 3 4;white:1 4 6 5"
  check_normals "perpendicular h=$h" "$obj" "0 1 0|0 0 1" || continue
  run_case "perpendicular common edge 1x1 emitter, 1x$h receiver" "$obj" 2 1 "$(ff "c14($h,1,1)")"
done

# 3. The c=1 parallel squares, each split into two triangles: faces 0,1 are
# the emitter, 2,3 the receiver.
obj=$T/tri.obj
write_scene "$obj" 1 "$SQUARE_E;0 0 1;1 0 1;1 1 1;0 1 1" \
  "light:1 2 3;light:1 3 4;white:5 8 7;white:5 7 6"
if check_normals "triangles" "$obj" "0 0 1|0 0 1|0 0 -1|0 0 -1"; then
  run_case "parallel unit squares c=1 as triangles" "$obj" 4 "2 3" "$(ff "c11(1,1,1)")" "0 1"
fi

# 4. The c=1 parallel squares scaled: form factors do not change.
for s in 1e-3 1e3; do
  obj=$T/scaled_$s.obj
  write_scene "$obj" "$s" "$SQUARE_E;0 0 1;1 0 1;1 1 1;0 1 1" "light:1 2 3 4;white:5 8 7 6"
  check_normals "scaled $s" "$obj" "0 0 1|0 0 -1" || continue
  run_case "parallel unit squares c=1 scaled by $s" "$obj" 2 1 "$(ff "c11(1,1,1)")"
done

finish
