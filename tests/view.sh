#!/bin/bash
# The browser view (--view, view.html; man page, VIEW): a real run of the
# Cornell box with --view, looked at in headless Chromium while it runs
# (the picture shows the scene, its shot count and picture move, its
# numbers are log.csv's), its view.html after it (the OBJ camera's picture
# matches final.png, exposure and walking work), the server's endpoints
# with curl, and hostile HTTP meanwhile (tests/http_abuse.py); the run,
# stopped with SIGINT once the page has seen it live and the abuse is done,
# must end with the result.csv of the same run without --view to the same
# shot. One Chromium for it all (tests/view_page.py): starting it is the
# slow part.
# Skipped (77) where Chromium is not installed (tests/deps.sh installs it).
. "$(dirname "$0")/lib.sh"
here=$(cd "$(dirname "$0")" && pwd)
scene=$here/../scenes/cornell.obj

if ! command -v chromium >/dev/null 2>&1; then
  echo "skip: no chromium (tests/deps.sh installs it; apt-get install chromium)"
  exit 77
fi
for tool in curl python3; do
  command -v "$tool" >/dev/null 2>&1 || { echo "skip: no $tool"; exit 77; }
done

# -j 0: reproducible bit for bit, so that a run to the same shot count
# gives the same result.csv. At R 512 with a target it does not reach, it
# runs while the page is looked at (the page is ready about 3 s after the
# start on an idle machine; Chromium once took 20 s to start beside other
# tests) and is stopped (SIGINT, which writes every result) as soon as the
# page and the abuse are done with it. 40000 shots (some 80 s on an idle
# machine) only bound a page that never says it is done. One wave
# (--no-subdivide): at a wave's end the page holds that wave's picture
# until the next wave is as far, which could outlast the run.
args=(-j 0 -e 1e-15 -r 512 --no-subdivide "$scene")
: >"$T/live.err"  # there before the program opens it: waited on below
bg_run live -q --view 127.0.0.1:0 -s 40000 "${args[@]}"
if ! wait_says live 'view on http://'; then
  fail "--view says where it serves (stderr: $(head -3 "$T/live.err"))"
  finish
fi
url=$(sed -n 's|^radiosity: view on \(http://[^ ]*/\)$|\1|p' "$T/live.err")
port=${url##*:}; port=${port%/}
pass "--view 127.0.0.1:0 says where it serves ($url)"

# The endpoints, as a client sees them.
code=$(curl -s -o "$T/page.html" -w '%{http_code} %{content_type}' "$url")
if [ "$code" = "200 text/html; charset=utf-8" ] && grep -q 'WebGL' "$T/page.html" &&
   ! grep -q 'src="view.js"' "$T/page.html"; then
  pass "GET / is the page with its script in it ($code)"
else fail "GET / is the page with its script in it (got $code)"; fi
# The server is up before the run's first log row (shot 0) is in: asked
# again until it is (a run at load 8 once answered with no rows).
state_rows() { curl -s -o "$T/state.json" "${url}state.json" && grep -q '"rows":\[\[' "$T/state.json"; }
wait_until 20 state_rows || fail "GET /state.json with a log row (within 20 s)"
if python3 - "$T/state.json" <<'EOF'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["scene"] == "cornell.obj" and s["status"] == "running", s["status"]
assert s["camera"]["eye"] == [278, 273, -800] and s["camera"]["width"] == 512, s["camera"]
assert s["first"] == 0 and len(s["rows"]) >= 1 and s["rows"][0][1] == 0, s["rows"][:1]
assert all(len(r) == 7 and r[5] is None for r in s["rows"])
EOF
then pass "GET /state.json: the run's scene, camera and log rows (JSON)"
else fail "GET /state.json: the run's scene, camera and log rows"; fi
code=$(curl -s -o "$T/mesh.bin" -w '%{http_code}' "${url}mesh.bin")
magic=$(head -c 4 "$T/mesh.bin")
if [ "$code" = 200 ] && [ "$magic" = RVW1 ]; then
  pass "GET /mesh.bin: a mesh snapshot ($(wc -c <"$T/mesh.bin") bytes)"
else fail "GET /mesh.bin: a mesh snapshot (got $code, magic '$magic')"; fi

# Abuse and the browser at the same time; each prints ok/FAIL lines.
python3 "$here/http_abuse.py" "$port" >"$T/abuse.out" 2>&1 &
abuse=$!
python3 "$here/view_page.py" "$url" "$T/live" "$PID" >"$T/page.out" 2>&1 &
page=$!
wait "$abuse"
abuse_rc=$?
# The page says when it is done with the live run (or ends); then the
# run is stopped, and the page goes on to the view.html it writes.
page_done() { grep -q '^# live page done' "$T/page.out" || ! kill -0 "$page" 2>/dev/null; }
wait_until "$(run_limit)" page_done
kill -INT "$PID" 2>/dev/null
wait "$PID"; rc=$?
# The same run without the view, to the shot the live one stopped at.
shots=$(awk -F, 'END { print $2 }' "$T/live/log.csv" 2>/dev/null)
run_rad "$T/plain" -s "${shots:-1}" "${args[@]}"
plain_rc=$RC
wait "$page"
page_rc=$?
relay() {
  while IFS= read -r line; do
    case $line in
      ok:*) pass "${line#ok: }" ;;
      FAIL:*) fail "${line#FAIL: }" ;;
      *) echo "$line" ;;
    esac
  done <"$1"
}
relay "$T/abuse.out"
relay "$T/page.out"
[ "$abuse_rc" -eq 0 ] || grep -q '^FAIL' "$T/abuse.out" || fail "http_abuse.py ended with $abuse_rc"
[ "$page_rc" -eq 0 ] || grep -q '^FAIL' "$T/page.out" || fail "view_page.py ended with $page_rc"

if [ "$rc" -eq 0 ] && [ "$plain_rc" -eq 0 ]; then pass "both runs exit 0"
else fail "both runs exit 0 (got $rc with --view, $plain_rc without; stderr: $(tail -2 "$T/live.err"))"; fi
if cmp -s "$T/live/result.csv" "$T/plain/result.csv"; then
  pass "result.csv with --view and the abuse is that of the run without --view ($shots shots)"
else fail "result.csv with --view differs from the run without it"; fi
if [ -s "$T/plain/view.html" ] && grep -q 'id="radiosity-mesh"' "$T/plain/view.html"; then
  pass "a run without --view writes view.html too ($(wc -c <"$T/plain/view.html") bytes)"
else fail "a run without --view writes view.html too"; fi
finish
