"""Headless Chromium driven over the DevTools protocol on a pipe
(--remote-debugging-pipe: JSON messages ending in NUL on fds 3 and 4), with
nothing but the Python standard library. One browser serves a whole test:
starting Chromium is the slow part.

    with Browser() as b:
        b.viewport(512, 512)
        b.open("http://127.0.0.1:8080/")
        b.wait("document.title !== ''", 10)
        title = b.eval("document.title")
"""

import fcntl
import json
import os
import select
import shutil
import subprocess
import tempfile
import time


def chromium():
    """The Chromium binary, or None."""
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    def __init__(self, timeout=30):
        self.timeout = timeout
        self.profile = tempfile.mkdtemp(prefix="radiosity-chromium.")
        # Our ends of the pipes above 9, so that the child's dup2 onto 3 and
        # 4 clobbers none of them.
        def high(fd):
            n = fcntl.fcntl(fd, fcntl.F_DUPFD_CLOEXEC, 10)
            os.close(fd)
            return n
        cmd_r, self.cmd_w = map(high, os.pipe())
        self.res_r, res_w = map(high, os.pipe())

        def child():
            os.dup2(cmd_r, 3)
            os.dup2(res_w, 4)

        self.proc = subprocess.Popen(
            [chromium(), "--headless", "--no-sandbox", "--disable-gpu-sandbox",
             # WebGL on the CPU (SwiftShader): a test machine has no GPU.
             "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
             "--no-first-run", "--no-default-browser-check", "--disable-extensions",
             "--disable-background-networking", "--disable-sync", "--mute-audio",
             "--remote-debugging-pipe", "--user-data-dir=" + self.profile, "about:blank"],
            pass_fds=(3, 4), preexec_fn=child, stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(cmd_r)
        os.close(res_w)
        self.buf = b""
        self.next_id = 0
        page = [t for t in self.call("Target.getTargets")["targetInfos"] if t["type"] == "page"]
        self.session = self.call("Target.attachToTarget",
                                 {"targetId": page[0]["targetId"], "flatten": True})["sessionId"]
        self.call("Page.enable", session=True)
        self.call("Runtime.enable", session=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        if self.proc.poll() is None:
            try:
                self.call("Browser.close")
            except (OSError, RuntimeError, TimeoutError):
                pass
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for fd in (self.cmd_w, self.res_r):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def call(self, method, params=None, session=False):
        """Sends a command and returns its result (events are dropped)."""
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = self.session
        os.write(self.cmd_w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + self.timeout
        while True:
            while b"\0" not in self.buf:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(method + ": no answer from Chromium")
                if not select.select([self.res_r], [], [], left)[0]:
                    continue
                chunk = os.read(self.res_r, 1 << 20)
                if not chunk:
                    raise RuntimeError(method + ": Chromium has gone")
                self.buf += chunk
            line, self.buf = self.buf.split(b"\0", 1)
            reply = json.loads(line)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(method + ": " + reply["error"].get("message", "error"))
                return reply.get("result", {})

    def viewport(self, width, height):
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
                  session=True)

    def open(self, url):
        self.call("Page.navigate", {"url": url}, session=True)

    def eval(self, expression):
        """The value of a JavaScript expression (awaited if a promise)."""
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                           "awaitPromise": True}, session=True)
        if "exceptionDetails" in r:
            raise RuntimeError("JavaScript: " + r["exceptionDetails"].get("exception", {}).get(
                "description", r["exceptionDetails"].get("text", "exception")))
        return r["result"].get("value")

    def wait(self, expression, seconds):
        """Until the expression is truthy (asked every 50 ms); its value, or
        None when it did not become true in time."""
        deadline = time.monotonic() + seconds
        while True:
            try:
                v = self.eval(expression)
            except RuntimeError:
                v = None
            if v:
                return v
            if time.monotonic() > deadline:
                return None
            time.sleep(0.05)
