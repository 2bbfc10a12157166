#!/bin/sh
# The form-factor column at scale: ms per column (CPU time) split into
# stages, against the cost model 15 ns/element + 70 ns/covered element +
# 3 ns/pixel (3 R² pixels), before and after side by side, at about 10^3,
# 10^4, 10^5 and 10^6 elements, on generated rooms of boxes (build/scenegen
# boxes N) and the Cornell box cut K x K and triangulated (scenegen
# tessellate; its faces kept apart, as with --no-join); "visited" is the
# share of elements on faces the column did not cull (before: every
# front-facing face).
#   sh bench/column.sh [quick]       quick: up to 10^5 elements
# BEFORE=REV (default 5298a27, the column before culling): REV's
# hemicube.{h,cpp} (and hemicube_cache.cpp where REV has it) built with bench/column.cpp against this tree's other
# objects into bench/results/tmp/ (a note instead if that no longer builds).
# R: resolution (default 256); COLUMNS: shooters per scene (default 40),
# spread evenly over the patches, or with FIRST=1 the first COLUMNS a run
# shoots (radiosity-column --first): the lights and large surfaces, which
# see most of a big scene and cost more than the average shooter.
# Scenes are generated once into bench/results/tmp/scenes/ (not in git).
cd "$(dirname "$0")/.." || exit 1
mode=${1:-full}
res=${R:-256}
n=${COLUMNS:-40}
rev=${BEFORE:-5298a27}
objs="build/clock.o build/scene.o build/surface.o build/mesh.o build/divide.o build/groups.o build/files.o build/memory.o build/solver.o build/shooters.o"
first=
[ -n "$FIRST" ] && first=--first
for b in build/radiosity-column build/scenegen $objs; do
  [ -e "$b" ] || { echo "bench/column.sh: $b missing: run make build/radiosity-column build/scenegen" >&2; exit 1; }
done
dir=bench/results/tmp/scenes
old=bench/results/tmp/column-$rev
mkdir -p "$dir" "$old"
if [ ! -x "$old/radiosity-column" ]; then
  # As the Makefile builds hemicube.o (vectorised), so that only the code differs.
  flags="$(pkg-config --cflags glm stb 2>/dev/null) -O2 -std=c++17 -ftree-vectorize -fvect-cost-model=dynamic"
  # shellcheck disable=SC2086 # flags
  { git show "$rev:hemicube.cpp" >"$old/hemicube.cpp" && git show "$rev:hemicube.h" >"$old/hemicube.h" &&
    ${CXX:-g++} $flags -I"$old" -I. -c -o "$old/hemicube.o" "$old/hemicube.cpp" &&
    ${CXX:-g++} $flags -I"$old" -I. -c -o "$old/column.o" bench/column.cpp &&
    # REV's cache too, where it has one of its own (split out of hemicube.cpp).
    cache= && if git cat-file -e "$rev:hemicube_cache.cpp" 2>/dev/null; then
      git show "$rev:hemicube_cache.cpp" >"$old/hemicube_cache.cpp" &&
        ${CXX:-g++} $flags -I"$old" -I. -c -o "$old/hemicube_cache.o" "$old/hemicube_cache.cpp" &&
        cache="$old/hemicube_cache.o"
    fi &&
    # shellcheck disable=SC2086 # objs, cache
    ${CXX:-g++} -o "$old/radiosity-column" "$old/column.o" $objs "$old/hemicube.o" $cache -lpthread; } \
    >"$old/build.log" 2>&1 || rm -f "$old/radiosity-column"
fi

scene() {  # NAME: generated on first use
  f=$dir/$1.obj
  if [ ! -s "$f" ]; then
    case $1 in
      boxes*) ./build/scenegen boxes "${1#boxes}" "$f" >/dev/null ;;
      cornell*t) k=${1#cornell}; ./build/scenegen tessellate scenes/cornell.obj "${k%t}" "$f" --tri >/dev/null ;;
    esac || exit 1
  fi
  echo "$f"
}

list="boxes20 cornell1t boxes1000 cornell3t boxes10000 cornell24t"
[ "$mode" = quick ] || list="$list boxes40000 cornell80t"
which="$n shooters"
[ -n "$first" ] && which="the first $n shooters of a run"
echo "Form-factor column at scale (R = $res, ms per column, CPU time, mean over $which; before: $rev)"
echo "| scene | elements | covered | model | before | before/model | before visited | after | after/model | after visited | transform | raster | readback |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
rows=$(mktemp)
trap 'rm -f "$rows"' EXIT
for s in $list; do
  f=$(scene "$s") || exit 1
  # The tessellated box's faces are kept apart (JOIN 0): joined, its
  # coplanar triangles would make the plain box again.
  case $s in cornell*t) args="0 2 0" ;; *) args="" ;; esac
  # Fields: name R elements covered visited ms transform raster readback model ratio
  # shellcheck disable=SC2086 # first, args
  after=$(./build/radiosity-column $first "$f" "$res" "$n" $args) || exit 1
  before="- | - | - | - | - | - | - | - | - | - | -"
  # shellcheck disable=SC2086 # first, args
  [ -x "$old/radiosity-column" ] && { before=$("$old/radiosity-column" $first "$f" "$res" "$n" $args) || exit 1; }
  echo "$before|$after" | awk -F' [|] |[|]' -v s="$s" '
    { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n",
        s, $14, $15, $21, $6, $11, $5, $17, $22, $16, $18, $19, $20 }'
  echo "$s,$before,$after" | tr -d ' ' | tr '|' ',' >>"$rows"
done
[ -x "$old/radiosity-column" ] || echo "(before: $rev's column did not build against this tree: $old/build.log)"
R_DIR=${RESULTS:-bench/results}
mkdir -p "$R_DIR"
{
  echo "scene,b_name,b_R,b_elements,b_covered,b_visited,b_ms,b_transform_ms,b_raster_ms,b_readback_ms,b_model_ms,b_ratio,name,R,elements,covered,visited,ms,transform_ms,raster_ms,readback_ms,model_ms,ratio"
  cat "$rows"
} >"$R_DIR/column-scale.csv"
echo
echo "CSV: $R_DIR/column-scale.csv"
