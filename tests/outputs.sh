#!/bin/bash
# What a run leaves and says besides result.csv: error.svg (well-formed,
# the expected series, a mark per new wave), --converge then --reference
# (the RMS columns of log.csv), result.ply parsed in full, result.gltf +
# result.bin checked for consistency, and progress on stderr (plain lines
# when it is a file, one line redrawn with \r on a terminal, nothing with -q).
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

SCENES=$(cd "$(dirname "$0")/../scenes" && pwd)
CB=$SCENES/cornell.obj
have_python=0
command -v python3 >/dev/null 2>&1 && have_python=1

# --converge: a converged result.csv saved where asked, the same as the run's own.
run_rad "$T/conv" -j 0 -r 64 --converge "$T/ref.csv" "$CB"
if [ "$RC" -eq 0 ] && cmp -s "$T/ref.csv" "$T/conv/result.csv"; then
  pass "--converge writes the run's result.csv to the file given"
else
  fail "--converge (exit $RC; $(head -1 "$T/conv.err"); $(ls "$T"))"
fi
last=$(tail -1 "$T/conv/log.csv" | cut -d, -f5)
awk -v u="$last" 'BEGIN { exit !(u < 1e-5) }' && pass "--converge runs to epsilon 1e-5 (last unshot $last)" \
  || fail "--converge epsilon (last unshot $last, want < 1e-5)"

# ... and --reference reads it: every log row has rms and rel_rms, falling.
run_rad "$T/ref" -j 0 -r 64 --seed 3 --reference "$T/ref.csv" "$CB"
empty=$(awk -F, 'NR > 1 && ($6 == "" || $7 == "") { n++ } END { print n + 0 }' "$T/ref/log.csv")
rows=$(($(wc -l <"$T/ref/log.csv") - 1))
first=$(sed -n 2p "$T/ref/log.csv" | cut -d, -f7)
final=$(tail -1 "$T/ref/log.csv" | cut -d, -f7)
if [ "$RC" -eq 0 ] && [ "$rows" -gt 3 ] && [ "$empty" -eq 0 ] &&
   awk -v a="$first" -v b="$final" 'BEGIN { exit !(a > 0.1 && b < 0.02 && b > 0) }'; then
  pass "--reference of a --converge file: $rows rows with rms, rel_rms from $first to $final"
else
  fail "--reference of a --converge file (exit $RC, $rows rows, $empty without rms, rel_rms $first to $final; want > 0.1 to (0, 0.02))"
fi

# A reference cut short is refused: exit 1, one line, no file.
run_rad "$T/short" -j 0 -r 64 -s 5 --converge "$T/short.csv" "$CB"
if [ "$RC" -eq 1 ] && [ ! -e "$T/short.csv" ] && [ "$(wc -l <"$T/short.err")" -eq 1 ] &&
   grep -q '^radiosity: --converge .*did not converge' "$T/short.err"; then
  pass "--converge stopped by -s: exit 1, not written ($(cat "$T/short.err"))"
else
  fail "--converge stopped by -s (exit $RC: $(head -c 300 "$T/short.err"))"
fi

# error.svg: XML, one line per series, the legend, a dashed mark per new wave.
svg_check() {  # NAME DIR SERIES_WANTED
  local name=$1 svg=$2/error.svg want=$3 lines waves marks
  if [ ! -s "$svg" ]; then fail "$name: no error.svg"; return; fi
  if command -v xmllint >/dev/null 2>&1; then
    xmllint --noout "$svg" 2>"$T/xml.err" && pass "$name: error.svg is well-formed XML (xmllint)" \
      || fail "$name: error.svg is not well-formed: $(head -2 "$T/xml.err")"
  else
    head -1 "$svg" | grep -q '^<svg ' && tail -1 "$svg" | grep -q '^</svg>$' \
      && pass "$name: error.svg starts with <svg and ends with </svg>" || fail "$name: error.svg frame"
  fi
  lines=$(grep -c '<polyline' "$svg")
  [ "$lines" -eq "$want" ] && pass "$name: $lines series drawn" || fail "$name: $lines series drawn, want $want"
  for label in "unshot fraction" "RMS error" "relative RMS error"; do
    if [ "$want" -eq 1 ] && [ "$label" != "unshot fraction" ]; then
      grep -q ">$label<" "$svg" && fail "$name: '$label' without a reference"
      continue
    fi
    grep -q ">$label<" "$svg" && pass "$name: legend has '$label'" || fail "$name: legend lacks '$label'"
  done
  waves=$(awk -F, 'NR > 2 && $3 != w { n++ } { w = $3 } END { print n + 0 }' "$2/log.csv")
  marks=$(grep -c 'stroke-dasharray="3 3"' "$svg")
  [ "$marks" -eq "$waves" ] && pass "$name: $marks wave marks for $waves new waves in log.csv" \
    || fail "$name: $marks wave marks, log.csv has $waves new waves"
}
svg_check "plain run" "$T/conv" 1
svg_check "with --reference" "$T/ref" 3
waves=$(tail -1 "$T/ref/log.csv" | cut -d, -f3)
[ "$waves" -gt 1 ] && pass "the run had $waves waves (marks tested)" || fail "want a run of several waves (got $waves)"

# result.ply in full: header counts, every vertex and face line, indices in range.
ply=$T/conv/result.ply
res=$(awk '
  NR == 1 { if ($0 != "ply") { print "not ply"; exit } next }
  !body && /^element vertex / { nv = $3 } !body && /^element face / { nf = $3 }
  !body && /^format / { if ($2 != "ascii") { print "format " $2; exit } }
  !body && /^end_header$/ { body = 1; next }
  body && v < nv { if (NF != 6) { print "vertex line " NR ": " NF " fields"; exit }
    for (k = 4; k <= 6; k++) if ($k !~ /^[0-9]+$/ || $k > 255) { print "colour " $k " line " NR; exit }
    if ($4 + $5 + $6 > 0) lit++
    v++; next }
  body && f < nf { if ($1 != 3 && $1 != 4 || NF != $1 + 1) { print "face line " NR; exit }
    for (k = 2; k <= NF; k++) if ($k < 0 || $k >= nv) { print "index " $k " line " NR; exit }
    f++; next }
  body { print "extra line " NR; exit }
  END { if (v != nv || f != nf || nv == 0) print "counts " v "/" nv " " f "/" nf; else print "ok " nv " " nf " " lit }' "$ply")
case $res in
  ok*) set -- $res; [ "$4" -gt 0 ] && pass "result.ply parses: $2 vertices, $3 faces, $4 lit" || fail "result.ply: every vertex black" ;;
  *) fail "result.ply: $res" ;;
esac

# result.gltf + result.bin: counts, byte lengths and offsets agree, indices in range.
if [ "$have_python" = 1 ]; then
  out=$(python3 - "$T/conv/result.gltf" <<'EOF' 2>&1
import json, os, struct, sys
path = sys.argv[1]
g = json.load(open(path))
assert g["asset"]["version"] == "2.0", "asset.version"
buf = g["buffers"][0]
data = open(os.path.join(os.path.dirname(path), buf["uri"]), "rb").read()
assert len(data) == buf["byteLength"], "bin is %d bytes, byteLength %d" % (len(data), buf["byteLength"])
prim = g["meshes"][0]["primitives"][0]
size = {5126: 4, 5125: 4}
comps = {"VEC3": 3, "SCALAR": 1}
acc = g["accessors"]
for a in acc:
    bv = g["bufferViews"][a["bufferView"]]
    need = a["count"] * comps[a["type"]] * size[a["componentType"]]
    assert need == bv["byteLength"], "accessor needs %d bytes, view has %d" % (need, bv["byteLength"])
    assert bv["byteOffset"] + bv["byteLength"] <= len(data), "view past the buffer"
    assert bv["byteOffset"] % 4 == 0, "misaligned view"
pos, col, idx = acc[prim["attributes"]["POSITION"]], acc[prim["attributes"]["COLOR_0"]], acc[prim["indices"]]
assert pos["count"] == col["count"], "COLOR_0 and POSITION counts differ"
assert idx["count"] % 3 == 0 and prim.get("mode", 4) == 4, "not triangles"
def floats(a):
    bv = g["bufferViews"][a["bufferView"]]
    return struct.unpack_from("<%df" % (a["count"] * 3), data, bv["byteOffset"])
p = floats(pos)
for k in range(3):
    lo, hi = min(p[k::3]), max(p[k::3])
    assert abs(lo - pos["min"][k]) <= 1e-6 * (1 + abs(lo)) and abs(hi - pos["max"][k]) <= 1e-6 * (1 + abs(hi)), "min/max"
c = floats(col)
assert all(0 <= v <= 1 for v in c), "colour outside [0, 1]"
assert max(c) > 0, "every colour black"
bv = g["bufferViews"][idx["bufferView"]]
ids = struct.unpack_from("<%dI" % idx["count"], data, bv["byteOffset"])
assert max(ids) < pos["count"], "index out of range"
print("%d vertices, %d triangles" % (pos["count"], idx["count"] // 3))
EOF
  ) && pass "result.gltf: $out, counts and byte lengths agree" || fail "result.gltf: $out"
else
  [ -s "$T/conv/result.gltf" ] && [ -s "$T/conv/result.bin" ] && pass "result.gltf, result.bin written (no python3 to parse them)" \
    || fail "result.gltf or result.bin missing"
fi

# final.hdr beside final.png: Radiance RGBE of the picture's size, moved out
# of the run's private directory with the rest. --format exr: final.exr and
# the frames in OpenEXR (magic 76 2f 31 01), no final.png; a png run into the
# same directory then removes them, as any earlier run's outputs.
# (Pixels against result.csv: tests/exr_test.cpp.)
exr_magic() { head -c 4 "$1" 2>/dev/null | od -An -tx1 | tr -d ' \n'; }
if [ "$(head -1 "$T/conv/final.hdr")" = "#?RADIANCE" ] && grep -aqx -- '-Y 512 +X 512' "$T/conv/final.hdr" &&
   [ -s "$T/conv/final.png" ] && ! ls -A "$T/conv" | grep -q '^\.radiosity-'; then
  pass "final.hdr beside final.png: Radiance RGBE, 512x512, nothing left in a staging directory"
else
  fail "final.hdr: $(head -c 80 "$T/conv/final.hdr" | tr '\n' '|'); $(ls -A "$T/conv" | tr '\n' ' ')"
fi
run_rad "$T/exr" -j 0 -r 32 -s 30 --size 64x48 --format exr "$CB"
frames=$(cd "$T/exr" && ls frame-*.exr 2>/dev/null | wc -l)
if [ "$RC" -eq 0 ] && [ "$(exr_magic "$T/exr/final.exr")" = 762f3101 ] && [ "$frames" -ge 1 ] &&
   [ "$(exr_magic "$T/exr/frame-01.exr")" = 762f3101 ] && [ ! -e "$T/exr/final.png" ] &&
   grep -aqx -- '-Y 48 +X 64' "$T/exr/final.hdr"; then
  pass "--format exr: final.exr and $frames frame-NN.exr in OpenEXR, final.hdr 64x48, no final.png"
else
  fail "--format exr (exit $RC): $(ls "$T/exr" | tr '\n' ' ')"
fi
run_rad "$T/exr" -j 0 -r 32 -s 30 --size 64x48 "$CB"
left=$(cd "$T/exr" && ls final.exr frame-*.exr 2>/dev/null | tr '\n' ' ')
if [ "$RC" -eq 0 ] && [ -z "$left" ] && [ -s "$T/exr/final.png" ] && [ -s "$T/exr/final.hdr" ]; then
  pass "a png run after an exr one: final.png and final.hdr, the EXR files removed"
else
  fail "a png run after an exr one (exit $RC) left: $left; has $(ls "$T/exr" | tr '\n' ' ')"
fi

# Progress: to a file, plain lines (no \r); with -q, nothing.
timeout "$(run_limit)" "$RADIOSITY" -o "$T/prog" -j 1 -r 64 "$CB" >/dev/null 2>"$T/prog.err"; rc=$?
n=$(grep -c '^radiosity: wave [0-9]* | [0-9]* shots | .* | [0-9]* workers* | ' "$T/prog.err")
if [ "$rc" -eq 0 ] && [ "$n" -ge 1 ] && ! grep -q $'\r' "$T/prog.err" && grep -q 'worker 1 .*joined' "$T/prog.err"; then
  pass "progress to a file: $n plain lines, a join message ($(grep -m1 '| wave\|wave' "$T/prog.err"))"
else
  fail "progress to a file (exit $rc, $n lines): $(head -c 400 "$T/prog.err")"
fi
timeout "$(run_limit)" "$RADIOSITY" -q -o "$T/quiet" -j 1 -r 64 "$CB" >/dev/null 2>"$T/quiet.err"
[ ! -s "$T/quiet.err" ] && pass "-q: stderr empty" || fail "-q: stderr has $(head -c 200 "$T/quiet.err")"
# On a terminal (script(1) gives a pty): \r-redrawn line.
if command -v script >/dev/null 2>&1; then
  script -qec "timeout $(run_limit) '$RADIOSITY' -o '$T/tty' -j 0 -r 64 --log-every 1 '$CB' >/dev/null" /dev/null >"$T/tty.out" 2>&1
  if grep -q $'\rwave [0-9]* | [0-9]* shots' "$T/tty.out" && grep -q 'converged' "$T/tty.out"; then
    pass "progress on a terminal: redrawn with \\r ($(grep -o $'\r' "$T/tty.out" | wc -l) returns)"
  else
    fail "progress on a terminal: $(tr '\r' '|' <"$T/tty.out" | head -c 400)"
  fi
else
  echo "skip: no script(1) for the terminal check"
fi

finish
