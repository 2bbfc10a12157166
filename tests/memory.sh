#!/bin/bash
# Memory limits (man page, LIMITS): a scene that would not fit in the
# memory this process may use (physical memory, ulimit -v, a cgroup) is
# refused at load with one line and exit 2, not killed half-way; a worker
# that cannot hold it says so to the master in one line. The limit is set
# with ulimit -v, so the scenes stay small and the test quick.
. "$(dirname "$0")/lib.sh"
ROOM=$(dirname "$0")/../scenes/room.obj

# The room cut fine: about 1.1e6 elements, 0.55 GB at the master's rate.
(ulimit -v 400000; "$RADIOSITY" -j 0 -q -o "$T/big" --patch-size 0.04 "$ROOM" >"$T/out" 2>"$T/err")
status=$?
lines=$(wc -l <"$T/err")
if [ "$status" -eq 2 ] && [ "$lines" -eq 1 ] && grep -q "^radiosity: .*room.obj: about .* elements would need about .* GB (.* bytes each), more than the .* GB this process may use$" "$T/err"; then
  pass "a scene too large for ulimit -v is refused at load (exit $status, $(cat "$T/err"))"
else
  fail "a scene too large for ulimit -v (exit $status, want 2; $lines lines: $(head -c 300 "$T/err"))"
fi
[ ! -e "$T/big/result.csv" ] && pass "nothing written for it" || fail "result.csv written for a refused scene"

# The same scene at the default size under that limit runs.
(ulimit -v 400000; "$RADIOSITY" -j 0 -q -s 5 -o "$T/small" "$ROOM" 2>"$T/err2")
status=$?
[ "$status" -eq 0 ] && [ -s "$T/small/result.csv" ] && pass "the room at the default size fits (exit $status)" \
  || fail "the room at the default size under ulimit -v 400000 (exit $status: $(head -c 300 "$T/err2"))"

# A worker under a tighter limit than its master refuses the scene with its one line.
printf '#!/bin/sh\nulimit -v 30000\nexec "%s" "$@"\n' "$RADIOSITY" >"$T/lowmem.sh"
chmod +x "$T/lowmem.sh"
"$RADIOSITY" -j 1 -s 1 -o "$T/w" --patch-size 0.1 --worker-cmd "$T/lowmem.sh" "$ROOM" 2>"$T/err3"
if grep -q "local worker 1 (pid [0-9]*): says: about .* elements would need about .* GB (225 bytes each)" "$T/err3"; then
  pass "a worker without the memory says so ($(grep says "$T/err3" | head -1))"
else
  fail "a worker without the memory: $(head -c 400 "$T/err3")"
fi
finish
