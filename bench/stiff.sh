#!/bin/bash
# Size (issue 7): a unit room whose floor is an N x N grid of quads
# (tests/make_stiff.awk scene "big"), loaded and shot a few times with
# -j 0; prints faces, elements, peak RSS (from /proc via /usr/bin/time, or
# bash's own rusage), bytes per element and seconds.
#   bash bench/stiff.sh [N...]        (default 448: 200,709 faces)
cd "$(dirname "$0")/.." || exit 1
RAD=${RADIOSITY:-$PWD/radiosity}
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
[ $# -gt 0 ] || set -- 448
printf '%-8s %-9s %-9s %-10s %-9s %-7s %s\n' n faces elements peak_MB B/elem seconds options
for n in "$@"; do
  awk -v scene=big -v n="$n" -v mtl="$T/big.mtl" -f tests/make_stiff.awk >"$T/big.obj"
  faces=$(grep -c '^f ' "$T/big.obj")
  for opts in "-s 5 --no-subdivide" "-s 5"; do
    t0=$(date +%s.%N)
    if [ -x /usr/bin/time ]; then
      /usr/bin/time -f '%M' -o "$T/rss" "$RAD" -v -j 0 $opts -o "$T/out" "$T/big.obj" 2>"$T/err"
      kb=$(tail -1 "$T/rss")
    else
      "$RAD" -v -j 0 $opts -o "$T/out" "$T/big.obj" 2>"$T/err"; kb=0
    fi
    t1=$(date +%s.%N)
    elems=$(sed -n 's/.* patches, \([0-9]*\) elements.*/\1/p' "$T/err" | head -1)
    awk -v n="$n" -v f="$faces" -v e="$elems" -v kb="$kb" -v a="$t0" -v b="$t1" -v o="$opts" 'BEGIN {
      printf "%-8s %-9s %-9s %-10.0f %-9.0f %-7.1f %s\n", n, f, e, kb / 1024, kb * 1024 / e, b - a, o }'
  done
done
