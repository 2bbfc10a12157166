"""The browser view in a real browser (tests/view.sh): headless Chromium
looks at the live page of a running `radiosity --view` and, once the run
has written its outputs, at its view.html, and prints one line per check
(ok: ... / FAIL: ...), as tests/lib.sh does.

usage: view_page.py URL OUTDIR PID
  URL     the live page (what the program printed after "view on")
  OUTDIR  the run's -o directory: view.html, final.png and log.csv are
          read from there once view.html appears
  PID     the run's process: view.html is waited for while it runs
"""

import base64
import csv
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.dont_write_bytecode = True  # no __pycache__ in the tree
from cdp import Browser  # noqa: E402

# The picture from the OBJ camera against final.png (8-bit sRGB values):
# both draw the same vertex colours with perspective-correct Gouraud
# shading and the same sRGB curve, so only float rounding and which pixel
# an edge's centre falls in differ. Measured on the Cornell box (SwiftShader):
# mean 0.043, 0.05% of the pixels off by more than 16 (edges, and a few
# pixels where one of the two has a crack between faces and the other
# not); allowed ten and twenty times that.
MEAN_TOLERANCE = 0.5
BAD_LEVEL = 16
BAD_TOLERANCE = 0.01

# Helpers in the page: the WebGL canvas' pixels, their spread, and the
# difference from a PNG given as a data: URL.
HELPERS = r"""
window.__test = {
  canvas() { return document.getElementById('view'); },
  pixels(src, w, h) {
    const k = document.createElement('canvas');
    k.width = w; k.height = h;
    const x = k.getContext('2d');
    x.drawImage(src, 0, 0);
    return x.getImageData(0, 0, w, h).data;
  },
  stats() {
    const c = this.canvas(), d = this.pixels(c, c.width, c.height);
    const colours = new Set();
    let lit = 0, sum = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (d[i] + d[i + 1] + d[i + 2] > 30) lit++;
      sum += d[i] + d[i + 1] + d[i + 2];
      colours.add((d[i] >> 3) << 10 | (d[i + 1] >> 3) << 5 | d[i + 2] >> 3);
    }
    const n = d.length / 4;
    return {w: c.width, h: c.height, colours: colours.size, lit: lit / n, mean: sum / (3 * n)};
  },
  // The canvas as a PNG data: URL, to compare on a page without the
  // view's Content-Security-Policy (which lets in no image).
  png() { return this.canvas().toDataURL('image/png'); },
  panel() {
    const v = (id) => document.getElementById(id).dataset.value;
    return {wave: v('wave'), shots: v('shots'), unshot: v('unshot'), elements: v('elements'),
            seconds: v('time'), status: document.getElementById('status').textContent,
            snapshot: this.canvas().dataset.snapshot};
  },
  frames() { return Number(this.canvas().dataset.frames || 0); },
};
true
"""

# On about:blank: two PNG data: URLs, pixel by pixel.
COMPARE = r"""
(async (a, b) => {
  const load = async (url) => {
    const img = new Image();
    img.src = url;
    await img.decode();
    const k = document.createElement('canvas');
    k.width = img.width; k.height = img.height;
    const x = k.getContext('2d');
    x.drawImage(img, 0, 0);
    return {w: img.width, h: img.height, d: x.getImageData(0, 0, img.width, img.height).data};
  };
  const p = await load(a), q = await load(b);
  if (p.w !== q.w || p.h !== q.h) return {size: p.w + 'x' + p.h + ' against ' + q.w + 'x' + q.h};
  let sum = 0, bad = 0, max = 0;
  for (let i = 0; i < p.d.length; i += 4) {
    let worst = 0;
    for (let k = 0; k < 3; k++) {
      const e = Math.abs(p.d[i + k] - q.d[i + k]);
      sum += e;
      worst = Math.max(worst, e);
    }
    if (worst > %d) bad++;
    max = Math.max(max, worst);
  }
  const n = p.d.length / 4;
  return {mean: sum / (3 * n), bad: bad / n, max};
})
""" % BAD_LEVEL

FAILS = 0


def ok(what):
    print("ok: " + what, flush=True)


def fail(what):
    global FAILS
    FAILS += 1
    print("FAIL: " + what, flush=True)


def check(cond, what, why=""):
    (ok if cond else fail)(what + ("" if cond or not why else " (" + why + ")"))
    return cond


def load(b, url):
    b.open(url)
    # Drawn: a mesh snapshot is on the canvas.
    if not b.wait("document.getElementById('view') && document.getElementById('view').dataset.snapshot", 30):
        return False
    b.eval(HELPERS)
    return True


def log_rows(outdir):
    with open(os.path.join(outdir, "log.csv"), newline="") as f:
        return list(csv.DictReader(f))


def in_log(panel, rows):
    """The log.csv row the panel shows, or None."""
    for r in rows:
        if (r["shots"] == panel["shots"] and int(r["wave"]) == int(panel["wave"]) and
                int(r["elements"]) == int(panel["elements"]) and
                float(r["unshot_fraction"]) == float(panel["unshot"]) and
                float(r["time_s"]) == float(panel["seconds"])):
            return r
    return None


def live(b, url):
    t0 = time.monotonic()
    if not check(load(b, url), "the live page draws the run's mesh"):
        return None
    print("# drawn in %.1f s" % (time.monotonic() - t0), flush=True)
    s = b.eval("__test.stats()")
    check(s["colours"] >= 100 and s["lit"] >= 0.3,
          "the live picture shows the scene (%d colours, %.0f%% of the pixels lit)" % (s["colours"], 100 * s["lit"]),
          "want at least 100 colours and 30% lit")
    p1 = b.eval("__test.panel()")
    # The page asks every half second; a new picture comes at most once a second.
    moved = b.wait("Number(__test.panel().shots) > %s && __test.panel().snapshot !== '%s' && __test.panel()" %
                   (p1["shots"], p1["snapshot"]), 60)
    print("# moved in %.1f s" % (time.monotonic() - t0), flush=True)
    if check(bool(moved), "the page's shot count and picture move while the run goes on",
             "stayed at %s shots, snapshot %s" % (p1["shots"], p1["snapshot"])):
        ok("  shots %s -> %s, snapshot %s -> %s" % (p1["shots"], moved["shots"], p1["snapshot"], moved["snapshot"]))
    return b.eval("__test.panel()")


def offline(b, outdir):
    if not check(load(b, "file://" + os.path.abspath(os.path.join(outdir, "view.html"))),
                 "view.html draws the final mesh from file://"):
        return
    drawn = b.eval("__test.png()")
    rows = log_rows(outdir)
    panel = b.eval("__test.panel()")
    last = rows[-1]
    check(in_log(panel, rows[-1:]) is not None,
          "view.html's panel shows log.csv's last row (%s shots, unshot %s, wave %s, %s elements)" %
          (panel["shots"], panel["unshot"], panel["wave"], panel["elements"]),
          "log.csv ends with %s shots, unshot %s" % (last["shots"], last["unshot_fraction"]))
    # Exposure: linear values scaled before the sRGB curve; one stop down
    # must darken the picture.
    before = b.eval("__test.stats()")["mean"]
    b.eval("(() => { const s = document.getElementById('exposure'); s.value = -1;"
           " s.dispatchEvent(new Event('input')); return true; })()")
    frames = b.eval("__test.frames()")
    b.wait("__test.frames() > %d" % frames, 5)
    after = b.eval("__test.stats()")["mean"]
    check(after < 0.9 * before, "the exposure slider, one stop down, darkens the picture "
          "(mean %.1f -> %.1f)" % (before, after))
    # Walking: W moves the eye; R goes back to the OBJ camera.
    frames = b.eval("__test.frames()")
    b.call("Input.dispatchKeyEvent", {"type": "keyDown", "key": "w", "code": "KeyW", "text": "w"}, session=True)
    b.wait("__test.frames() > %d" % (frames + 5), 5)
    b.call("Input.dispatchKeyEvent", {"type": "keyUp", "key": "w", "code": "KeyW"}, session=True)
    walked = b.eval("__test.stats()")["mean"]
    b.call("Input.dispatchKeyEvent", {"type": "keyDown", "key": "r", "code": "KeyR", "text": "r"}, session=True)
    b.call("Input.dispatchKeyEvent", {"type": "keyUp", "key": "r", "code": "KeyR"}, session=True)
    frames = b.eval("__test.frames()")
    b.wait("__test.frames() > %d" % frames, 5)
    back = b.eval("__test.stats()")["mean"]
    check(walked != after and back == after,
          "W walks into the scene and R returns to the OBJ camera (mean %.2f, walked %.2f, back %.2f)" %
          (after, walked, back))
    # The picture from the OBJ camera at the automatic exposure, against final.png.
    with open(os.path.join(outdir, "final.png"), "rb") as f:
        png = "data:image/png;base64," + base64.b64encode(f.read()).decode()
    b.open("about:blank")
    b.wait("document.readyState === 'complete'", 5)
    c = b.eval("%s(%r, %r)" % (COMPARE, drawn, png))
    if "size" in c:
        fail("view.html's canvas is final.png's size (" + c["size"] + ")")
    else:
        check(c["mean"] <= MEAN_TOLERANCE and c["bad"] <= BAD_TOLERANCE,
              "view.html from the OBJ camera matches final.png (mean difference %.3f of 255, "
              "%.2f%% of the pixels off by more than %d, at most %d; tolerance %.1f and %.0f%%)" %
              (c["mean"], 100 * c["bad"], BAD_LEVEL, c["max"], MEAN_TOLERANCE, 100 * BAD_TOLERANCE))


def running(pid):
    """Whether process PID runs (an ended child its parent has not reaped
    yet is a zombie, state Z, and counts as ended)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def main():
    url, outdir, pid = sys.argv[1], sys.argv[2], int(sys.argv[3])
    width, height = 512, 512
    t0 = time.monotonic()
    with Browser() as b:
        print("# chromium up in %.1f s" % (time.monotonic() - t0), flush=True)
        b.viewport(width, height)
        panel = live(b, url)
        print("# live page done at %.1f s" % (time.monotonic() - t0), flush=True)
        # The run's outputs appear together when it has written them all;
        # waited for until they are there or the run (process PID) has
        # ended, however long a loaded machine makes it take.
        while not os.path.exists(os.path.join(outdir, "view.html")) and running(pid):
            time.sleep(0.1)
        if panel:
            check(in_log(panel, log_rows(outdir)) is not None,
                  "the live panel's numbers are a row of log.csv (%s shots, unshot %s, wave %s, "
                  "%s elements, %s s)" % (panel["shots"], panel["unshot"], panel["wave"],
                                          panel["elements"], panel["seconds"]))
        offline(b, outdir)
    print("# browser done at %.1f s" % (time.monotonic() - t0), flush=True)
    return 1 if FAILS else 0


if __name__ == "__main__":
    sys.exit(main())
