#!/bin/bash
# End-to-end test of scene input on the real binary: every malformed scene
# must end with exit status 2, exactly one "radiosity: FILE:LINE: ..." line
# on stderr and no result.csv, within 20 s; every accepted variant of the
# two-parallel-unit-squares scene must give the receiver the analytic form
# factor (Howell C-11) within 3%.
# Usage: RADIOSITY=/abs/path/to/radiosity bash tests/scene_input.sh
set -u

RADIOSITY=${RADIOSITY:-$(dirname "$0")/../radiosity}
if [ ! -x "$RADIOSITY" ]; then
  echo "SKIP: no executable radiosity at '$RADIOSITY' (set RADIOSITY)"
  exit 77
fi
RADIOSITY=$(cd "$(dirname "$RADIOSITY")" && pwd)/$(basename "$RADIOSITY")

tmp=$(mktemp -d) || exit 1
trap 'rm -rf "$tmp"' EXIT
c=$tmp/c  # the case being run
failures=0
fail() {
  echo "FAIL: $*"
  failures=$((failures + 1))
}

fresh() {
  rm -rf "$c" "$tmp/out"
  mkdir -p "$c"
}

# ---- malformed input ------------------------------------------------------

# reject NAME REGEX: runs bad.obj (written by the caller into $c) and checks
# the exit status, that stderr is one line matching REGEX, and no result.csv.
reject() {
  local name=$1 re=$2 status lines
  (cd "$c" && timeout 20 "$RADIOSITY" -q -o "$tmp/out" "$c/bad.obj") >"$tmp/stdout" 2>"$tmp/stderr"
  status=$?
  if [ "$status" = 124 ]; then fail "$name: no answer within 20 s"; return; fi
  [ "$status" = 2 ] || fail "$name: exit status $status, want 2"
  lines=$(wc -l <"$tmp/stderr")
  if [ "$lines" != 1 ] || [ -n "$(tail -c 1 "$tmp/stderr")" ]; then
    fail "$name: stderr is not exactly one line: $(head -c 300 "$tmp/stderr" | tr '\n' '|')"
  elif ! grep -Eq "$re" "$tmp/stderr"; then
    fail "$name: stderr '$(cat "$tmp/stderr")' does not match '$re'"
  fi
  [ -e "$tmp/out/result.csv" ] && fail "$name: result.csv was written"
}

# bad_obj NAME LINE CONTENT: an OBJ that must fail on LINE of bad.obj.
bad_obj() {
  fresh
  printf '%s' "$3" >"$c/bad.obj"
  reject "$1" "^radiosity: .*bad\.obj:$2: "
}

# bad_mtl NAME LINE MTL: an MTL that must fail on LINE of bad.mtl.
bad_mtl() {
  fresh
  printf 'mtllib bad.mtl\n%susemtl m\nf 1 2 3 4\n' "$quad" >"$c/bad.obj"
  printf '%s' "$3" >"$c/bad.mtl"
  reject "$1" "^radiosity: .*bad\.mtl:$2: "
}

quad='v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
'
tri='v 0 0 0
v 1 0 0
v 0 1 0
'

# Whole-file problems name the file but no line.
fresh
reject "missing file" '^radiosity: .*bad\.obj'
fresh
: >"$c/bad.obj"
reject "empty file" '^radiosity: .*bad\.obj'
fresh
printf '# only comments\n%sl 1 2\n' "$tri" >"$c/bad.obj"
reject "no faces" '^radiosity: .*bad\.obj'


bad_obj "vertex index 0" 4 "${tri}f 0 1 2
"
bad_obj "vertex index out of range" 5 "${tri}f 1 2 3
f 1 2 4
"
bad_obj "negative index out of range" 4 "${tri}f -1 -2 -4
"
bad_obj "index before any v" 1 "f 1 2 3
${tri}"
bad_obj "index overflow" 4 "${tri}f 1 2 99999999999999999999
"
bad_obj "non-numeric index" 4 "${tri}f 1 2 three
"
bad_obj "malformed reference" 4 "${tri}f 1 2 3/1/1/1
"
bad_obj "NaN coordinate" 2 "v 0 0 0
v 1 nan 0
"
bad_obj "inf coordinate" 1 "v inf 0 0
"
bad_obj "overflowing coordinate" 3 "v 0 0 0
v 1 0 0
v 0 1e999 0
"
bad_obj "non-numeric coordinate" 1 "v 0 zero 0
"
bad_obj "missing coordinate" 2 "v 0 0 0
v 1 0
"
bad_obj "face with 2 vertices" 4 "${tri}f 1 2
"
bad_obj "bent quad (5%)" 5 "v 0 0 0
v 1 0 0
v 1 1 0.05
v 0 1 0
f 1 2 3 4
"
bad_obj "mtllib missing" 2 "# scene
mtllib nothere.mtl
${tri}f 1 2 3
"
bad_obj "usemtl undefined" 4 "${tri}usemtl nothing
f 1 2 3
"
bad_obj "malformed camera" 1 "# camera 0 0 5 0 0 0
${tri}f 1 2 3
"

# A long name is printed whole (issue 16: it was cut in the middle, and the
# missing file's own name lost): the scene and an mtllib, 300 characters.
deep=$c/$(printf '%090d' 0)/$(printf '%090d' 1)/$(printf '%090d' 2)
fresh
(cd "$c" && "$RADIOSITY" -q -o "$tmp/out" "$deep/does_not_exist.obj") >/dev/null 2>"$tmp/stderr"
[ "$(cat "$tmp/stderr")" = "radiosity: $deep/does_not_exist.obj: cannot open: No such file or directory" ] ||
  fail "a ${#deep}+-character scene path is not named whole: $(head -c 600 "$tmp/stderr")"
printf 'mtllib %s/does_not_exist.mtl\n%sf 1 2 3 4\n' "$deep" "$quad" >"$c/bad.obj"
reject "a 300-character mtllib path" "^radiosity: .*bad\.obj:1: mtllib: cannot open '$deep/does_not_exist\.mtl': No such"

bad_mtl "Kd above 1" 2 "newmtl m
Kd 1.5 0.5 0.5
"
bad_mtl "Kd NaN" 3 "newmtl m
Ke 1 1 1
Kd 0.5 nan 0.5
"
bad_mtl "Kd non-numeric" 2 "newmtl m
Kd white
"
bad_mtl "Ke negative" 2 "newmtl m
Ke -1 0 0
"
bad_mtl "Ke infinite" 2 "newmtl m
Ke inf
"

# Deterministic "random" bytes: a linear congruential generator, so a
# failure can be reproduced.
fresh
esc=""
x=12345
for ((i = 0; i < 4096; i++)); do
  x=$(((x * 1103515245 + 12345) % 2147483648))
  printf -v byte '\\%03o' $(((x >> 16) & 255))
  esc+=$byte
done
printf "$esc" >"$c/bad.obj"
reject "binary garbage" '^radiosity: .*bad\.obj:[0-9]+: '

fresh
printf 'v 0 0 0\nv 1 0\000 0\nv 0 1 0\nf 1 2 3\n' >"$c/bad.obj"
reject "NUL byte in a line" '^radiosity: .*bad\.obj:2: '

# ---- accepted variants of the two-squares scene ----------------------------

# Howell C-11: parallel directly opposed a x b rectangles at distance c.
want=$(awk 'BEGIN {
  X = 1; Y = 1; pi = atan2(0, -1)
  x2 = 1 + X * X; y2 = 1 + Y * Y
  F = log(sqrt(x2 * y2 / (x2 + Y * Y))) + X * sqrt(y2) * atan2(X, sqrt(y2)) \
    + Y * sqrt(x2) * atan2(Y, sqrt(x2)) - X * atan2(X, 1) - Y * atan2(Y, 1)
  printf "%.6f", 2 / (pi * X * Y) * F
}')

mtl='newmtl light
Kd 0 0 0
Ke 1 1 1
newmtl white
Kd 1 1 1
Ke 0 0 0
'
obj='mtllib scene.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 0 1 1
v 1 1 1
v 1 0 1
usemtl light
f 1 2 3 4
usemtl white
f 5 6 7 8
'

# accept NAME [RECEIVER_FACE [SCENE]]: runs SCENE (default scene.obj) from
# $c and checks the receiver's B_r (face RECEIVER_FACE, default 1).
accept() {
  local name=$1 face=${2:-1} scene=${3:-scene.obj} status got
  (cd "$c" && timeout 120 "$RADIOSITY" -q -o "$tmp/out" "$scene") >"$tmp/stdout" 2>"$tmp/stderr"
  status=$?
  if [ "$status" != 0 ]; then
    fail "$name: exit status $status: $(head -c 300 "$tmp/stderr" | tr '\n' '|')"
    return
  fi
  local header
  header=$(head -n 1 "$tmp/out/result.csv" 2>/dev/null | tr -d '\r')
  if [ "$header" != "face,object,area,B_r,B_g,B_b" ]; then
    fail "$name: result.csv missing or without its header"
    return
  fi
  got=$(awk -F, -v f="$face" 'NR > 1 && $1 == f { print $4 }' "$tmp/out/result.csv")
  if [ -z "$got" ]; then
    fail "$name: no row for face $face in result.csv"
  elif ! awk -v g="$got" -v w="$want" 'BEGIN { exit !(g >= 0.97 * w && g <= 1.03 * w) }'; then
    fail "$name: receiver B_r = $got, want $want within 3%"
  fi
}

# variant NAME OBJ MTL [RECEIVER_FACE]
variant() {
  fresh
  printf '%s' "$2" >"$c/scene.obj"
  printf '%s' "$3" >"$c/scene.mtl"
  accept "$1" "${4:-1}"
}

crlf() { printf '%s' "$1" | sed 's/$/\r/'; }
variant "plain" "$obj" "$mtl"
variant "CRLF line endings" "$(crlf "$obj")" "$(crlf "$mtl")"
variant "no trailing newline" "${obj%$'\n'}" "${mtl%$'\n'}"
variant "tabs, spaces, leading whitespace" "$(printf '%s' "$obj" | sed 's/ /\t  /g; s/^/ \t/')" \
  "$(printf '%s' "$mtl" | sed 's/ /  \t/g; s/^/\t /')"
variant "v/vt/vn and vt vn s l statements" "$(printf '%s' "$obj" |
  sed 's|^f \(.\) \(.\) \(.\) \(.\)$|f \1/1/1 \2/2/1 \3/3/1 \4/1/1|')
vt 0 0
vt 1 0
vt 1 1
vn 0 0 1
s 1
l 1 2
p 3
o after
g after
" "$mtl"
variant "v//vn and v/vt" "$(printf '%s' "$obj" |
  sed 's|^f 1 2 3 4$|f 1//1 2//1 3//1 4//1|; s|^f 5 6 7 8$|f 5/1 6/1 7/1 8/1|')" "$mtl"
variant "negative indices" "mtllib scene.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
usemtl light
f -4 -3 -2 -1
v 0 0 1
v 0 1 1
v 1 1 1
v 1 0 1
usemtl white
f -4 -3/-1 -2//-1 -1
" "$mtl"
variant "v x y z w" "$(printf '%s' "$obj" | sed 's/^\(v .*\)$/\1 1.0/')" "$mtl"
variant "grey Kd, missing Ke" "$obj" "newmtl light
Kd 0
Ke 1
newmtl white
Kd 1
"
variant "unknown MTL statements" "$obj" "# exported
newmtl light
Ns 96.0
Ka 1 1 1
Kd 0 0 0
Ks 0.5 0.5 0.5
Ke 1 1 1
Ni 1.45
d 1.0
Tr 0
illum 2
map_Kd light.png
newmtl white
Kd 1 1 1
illum 1
map_bump -bm 1 bump.png
"
long=$(printf '%*s' 100000 '' | tr ' ' 'x')
variant "100 kB comment lines" "# $long
$obj" "# $long
$mtl"
variant "receiver as a hexagon with collinear midpoints" "mtllib scene.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 0 0.5 1
v 0 1 1
v 1 1 1
v 1 0.5 1
v 1 0 1
usemtl light
f 1 2 3 4
usemtl white
f 5 6 7 8 9 10
" "$mtl"
variant "zero-area face before (face numbering)" "mtllib scene.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 0 1 1
v 1 1 1
v 1 0 1
v 0.5 0 0
f 1 9 2
usemtl light
f 1 2 3 4
usemtl white
f 5 6 7 8
" "$mtl" 2
# Repeated vertices (issue 16): f 1 1 2 has no area, a warning naming the
# file and line, the face skipped (and counted: the receiver is face 2);
# repeats in a row are dropped (f 1 2 2 3 4 is the quad).
variant "repeated vertices" "$(printf '%s' "$obj" |
  sed 's/^usemtl light$/f 5 5 6\nusemtl light/; s/^f 1 2 3 4$/f 1 2 2 3 4 4/; s/^f 5 6 7 8$/f 5 6 7 7 8/')
" "$mtl" 2
[ "$(cat "$tmp/stderr")" = "radiosity: warning: scene.obj:10: zero-area face skipped (2 distinct vertices)" ] ||
  fail "repeated vertices: stderr '$(head -c 300 "$tmp/stderr")', want the one zero-area warning"
variant "camera comment" "# camera 0.5 0.5 -3  0.5 0.5 0.5  40
$obj" "$mtl"
variant "UTF-8 byte order mark" $'\xEF\xBB\xBF'"$obj" "$mtl"

# The MTL is found next to the OBJ, not in the working directory.
fresh
mkdir "$c/sub"
printf '%s' "$obj" >"$c/sub/scene.obj"
printf '%s' "$mtl" >"$c/sub/scene.mtl"
accept "scene in a subdirectory" 1 sub/scene.obj

[ "$failures" = 0 ] || exit 1
exit 0
