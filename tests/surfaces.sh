#!/bin/bash
# Surfaces from faces (man page, MESH): the Blender-style room triangulated
# as an exporter writes it (scenegen tessellate scenes/blender.obj 2 --tri,
# made here) meshes as the plain room does and gives the same per-face
# results (its pieces folded back onto the room's faces, area-weighted)
# within 1%; with a worker too (the worker joins alike: the mesh hashes
# agree); result.csv keeps one row per input face; --no-join keeps every
# face a surface.
# shellcheck source=tests/lib.sh
. "$(dirname "$0")/lib.sh"

TOP=$(cd "$(dirname "$0")/.." && pwd)
GEN=$TOP/build/scenegen
if [ ! -x "$GEN" ]; then echo "skip: $GEN missing (make build/scenegen)"; exit 77; fi
"$GEN" tessellate "$TOP/scenes/blender.obj" 2 "$T/tri.obj" --tri 2>/dev/null \
  || { fail "scenegen tessellate"; finish; }
faces=$(grep -c '^f ' "$T/tri.obj")

run_ok "plain room" "$T/plain" -j 0 -v -r 128 --no-subdivide "$TOP/scenes/blender.obj" || finish
run_ok "triangulated room, a worker" "$T/tri" -j 1 -v -r 128 --no-subdivide "$T/tri.obj" || finish
csv_sane "triangulated room" "$T/tri/result.csv" "$faces"
mesh() { sed -n 's/^radiosity: [0-9]* faces, \([0-9]*\) surfaces, \([0-9]*\) patches, \([0-9]*\) elements.*/\1 \2 \3/p' "$1"; }
plain=$(mesh "$T/plain.err") tri=$(mesh "$T/tri.err")
[ -n "$plain" ] && [ "$plain" = "$tri" ] \
  && pass "$faces triangles mesh as the 26 faces do (surfaces, patches, elements: $tri)" \
  || fail "mesh of the triangulated room (got '$tri', want the plain room's '$plain')"
awk -v k=2 -v tri=1 -f "$TOP/tests/fold.awk" "$TOP/scenes/blender.obj" "$T/tri/result.csv" >"$T/folded.csv"
check_same "per face, the triangles' area-weighted mean against the plain room" \
  "$T/folded.csv" "$T/plain/result.csv" 1

run_rad "$T/nojoin" -j 0 -v -s 1 --no-join "$T/tri.obj"
got=$(mesh "$T/nojoin.err")
[ "${got%% *}" = "$faces" ] && pass "--no-join: every face a surface ($faces)" \
  || fail "--no-join (got surfaces '${got%% *}', want $faces)"
finish
