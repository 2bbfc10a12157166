#!/bin/sh
# Stands in for the radiosity binary to harvest the tests' scenes as seeds
# of scene_fuzz (fuzz/seeds/scene/): saves the scene of its command line
# (the OBJ, "%%MTL%%", its first MTL, mtllib renamed f.mtl) and exits 2.
#   RADIOSITY=$PWD/fuzz/harvest.sh HARVEST=$PWD/fuzz/seeds/scene bash tests/scene_input.sh
obj=""
for a in "$@"; do case $a in *.obj) obj=$a ;; esac; done
[ -n "$obj" ] && [ -f "$obj" ] || exit 2
mtl=$(awk '$1 == "mtllib" { print $2; exit }' "$obj")
{
  sed 's/^mtllib .*/mtllib f.mtl/' "$obj"
  if [ -n "$mtl" ] && [ -f "$(dirname "$obj")/$mtl" ]; then
    printf '\n%%%%MTL%%%%\n'
    cat "$(dirname "$obj")/$mtl"
  fi
} >"$HARVEST/tmp.$$"
sum=$(sha1sum <"$HARVEST/tmp.$$" | cut -c1-16)
mv "$HARVEST/tmp.$$" "$HARVEST/$sum"
exit 2
