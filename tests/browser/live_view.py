#!/usr/bin/env python3
"""The live page of a running scan, in a real browser.

Starts `gonio scan --sim --live` on the default grid, opens the page in
headless Chromium (driven over its DevTools pipe: the standard library
only), waits for the map to fill in, presses Pause, checks that nothing
more arrives while the head holds, presses Continue, and requires the scan
to end with every point and the page to say "finished". With a second
argument, saves a screenshot of the paused page there (the README's).

    python3 tests/browser/live_view.py target/debug/gonio [SHOT.png]

Prints one JSON object of what it saw; exits non-zero on any failure.
"""

import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time


class Browser:
    """Headless Chromium, spoken to in CDP messages over fds 3 and 4."""

    def __init__(self, exe, profile):
        to_child, self.tx = os.pipe()
        self.rx, from_child = os.pipe()

        def fds():
            os.dup2(to_child, 3)
            os.dup2(from_child, 4)

        self.proc = subprocess.Popen(
            [exe, "--headless=new", "--remote-debugging-pipe", "--no-sandbox", "--disable-gpu",
             "--no-first-run", f"--user-data-dir={profile}", "about:blank"],
            preexec_fn=fds, close_fds=False, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_child)
        os.close(from_child)
        self.next_id, self.buffer = 0, b""

    def call(self, method, params=None, session=None, timeout=30):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.tx, json.dumps(msg).encode() + b"\0")
        deadline = time.time() + timeout
        while time.time() < deadline:
            while b"\0" not in self.buffer:
                chunk = os.read(self.rx, 1 << 16)
                if not chunk:
                    raise RuntimeError("the browser closed its pipe")
                self.buffer += chunk
            raw, self.buffer = self.buffer.split(b"\0", 1)
            reply = json.loads(raw)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
        raise RuntimeError(f"{method}: no answer in {timeout} s")

    def close(self):
        self.proc.kill()
        self.proc.wait()


def wait_for(what, check, timeout=120):
    deadline = time.time() + timeout
    while time.time() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.1)
    raise RuntimeError(f"timed out waiting for {what}")


def main():
    gonio, shot = sys.argv[1], (sys.argv[2] if len(sys.argv) > 2 else None)
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if not exe:
        raise RuntimeError("no chromium on PATH (Debian: apt-get install chromium)")
    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()
    tmp = tempfile.mkdtemp()
    out = os.path.join(tmp, "scan")
    scan = subprocess.Popen([gonio, "scan", "--sim", "--out", out, "--live", "--json"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    browser = None
    try:
        live = os.path.join(out, "live.json")
        wait_for("live.json", lambda: os.path.exists(live) and os.path.getsize(live) > 0, 60)
        url = json.load(open(live))["url"]
        browser = Browser(exe, os.path.join(tmp, "profile"))
        target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        browser.call("Emulation.setDeviceMetricsOverride",
                     {"width": 1180, "height": 600, "deviceScaleFactor": 1, "mobile": False}, session)
        browser.call("Page.navigate", {"url": url}, session)

        def js(expr):
            r = browser.call("Runtime.evaluate", {"expression": expr, "returnByValue": True}, session)
            return r["result"].get("value")

        def samples():
            return js("window.live ? window.live.samples : 0") or 0

        wait_for("the map to fill in", lambda: samples() >= 1200)
        js("document.getElementById('pause').click()")
        wait_for("the page to say paused", lambda: js("window.live.state") == "paused")
        held = samples()
        time.sleep(1.5)
        if samples() != held:
            raise RuntimeError(f"{samples() - held} samples arrived while paused")
        if shot:
            png = browser.call("Page.captureScreenshot", {"format": "png"}, session)["data"]
            open(shot, "wb").write(base64.b64decode(png))
        js("document.getElementById('continue').click()")
        wait_for("samples after continue", lambda: samples() > held)
        wait_for("the page to say finished", lambda: js("window.live.state") == "finished", 600)
        stdout, stderr = scan.communicate(timeout=300)
        if scan.returncode != 0:
            raise RuntimeError(f"the scan failed ({scan.returncode}): {stderr}")
        outcome = json.loads(stdout)
        if outcome["measured"] + outcome["skipped"] != outcome["points"]:
            raise RuntimeError(f"points missing: {outcome}")
        if samples() != outcome["measured"]:
            raise RuntimeError(f"the page drew {samples()} samples of {outcome['measured']} measured")
        print(json.dumps({"browser": version, "points": outcome["points"], "measured": outcome["measured"],
                          "held_at": held, "drawn": samples(), "recoveries": outcome["recoveries"]}))
    finally:
        if browser:
            browser.close()
        if scan.poll() is None:
            scan.kill()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    try:
        main()
    except Exception as e:  # one line for CI's log, and a failing exit
        print(json.dumps({"error": str(e)}))
        sys.exit(1)
