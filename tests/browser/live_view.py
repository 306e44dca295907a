#!/usr/bin/env python3
"""The live page of a running scan, in a real browser, and a page that is
not it.

Starts `gonio scan --sim --live --pace 0.1` (the simulated head at a tenth
of the reference head's own time: a page can watch it fill in), opens the
page in headless Chromium (driven over its DevTools pipe: the standard
library only), and waits for samples. Then it attacks the scan as a web
page the user happened to open would: from another origin, a form POST
and no-cors fetches to /api/abort and /api/pause (one with the token in
the query), a cors read of /api/state with and without the token; and, as
a DNS-rebound name would, the page at http://localhost:PORT. None may
pause, abort or read the scan. Then the page's Pause button holds it,
`gonio continue DIR` continues it, `gonio pause DIR` holds it again, the
page's Continue button continues it, and the scan must end with every
point and the page saying "finished". With a second argument, saves a
screenshot of the paused page there (the README's).

    python3 tests/browser/live_view.py target/debug/gonio [SHOT.png]

Prints one JSON object of what it saw; exits non-zero on any failure.
"""

import base64
import http.server
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.error
import urllib.request


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


# What a page of another origin tries; it reports in window.attack.
EVIL = """<!doctype html><html><body>
<form id="f" method="POST" action="TARGET/api/abort" target="sink"><input name="x" value="1"></form>
<iframe name="sink"></iframe>
<script>
window.attack = {done: false};
const target = "TARGET", token = "TOKEN";
async function run() {
  document.getElementById("f").submit();
  const tries = [
    ["abort_no_cors", () => fetch(target + "/api/abort", {method: "POST", mode: "no-cors", body: "{}"})],
    ["pause_no_cors_token_in_query", () => fetch(target + "/api/pause?token=" + token,
        {method: "POST", mode: "no-cors", headers: {"Content-Type": "text/plain"}, body: "{}"})],
    ["pause_cors_json", () => fetch(target + "/api/pause",
        {method: "POST", headers: {"Content-Type": "application/json", "X-Gonio-Token": token}, body: "{}"})],
    ["read_state", () => fetch(target + "/api/state").then((r) => r.text())],
    ["read_state_token", () => fetch(target + "/api/state?token=" + token).then((r) => r.text())],
  ];
  for (const [name, f] of tries) {
    try { const r = await f(); window.attack[name] = (typeof r === "string") ? "read: " + r.slice(0, 40) : "opaque"; }
    catch (e) { window.attack[name] = "blocked"; }
  }
  window.attack.done = true;
}
run();
</script></body></html>"""


def serve_evil(html):
    """Serves `html` at http://127.0.0.1:PORT/ in a thread; returns PORT."""
    class Evil(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            body = html.encode()
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Evil)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server.server_address[1]


def state(live):
    """The scan's state, asked as its user (the origin and token of live.json)."""
    req = urllib.request.Request(f"{live['origin']}/api/state?token={live['token']}")
    return json.load(urllib.request.urlopen(req, timeout=10))


def main():
    gonio, shot = sys.argv[1], (sys.argv[2] if len(sys.argv) > 2 else None)
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if not exe:
        raise RuntimeError("no chromium on PATH (Debian: apt-get install chromium)")
    version = subprocess.run([exe, "--version"], capture_output=True, text=True).stdout.strip()
    tmp = tempfile.mkdtemp()
    out = os.path.join(tmp, "scan")
    scan = subprocess.Popen([gonio, "scan", "--sim", "--out", out, "--live", "--json", "--pace", "0.1",
                             "--theta-i", "30", "--theta-o", "0:60:3", "--dphi", "-180:180:30", "--no-patterns"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    browser = None
    try:
        live_file = os.path.join(out, "live.json")
        wait_for("live.json", lambda: os.path.exists(live_file) and os.path.getsize(live_file) > 0, 60)
        mode = os.stat(live_file).st_mode & 0o777
        if mode != 0o600:
            raise RuntimeError(f"live.json is readable beyond its user (mode {mode:o})")
        live = json.load(open(live_file))
        browser = Browser(exe, os.path.join(tmp, "profile"))

        def tab(url):
            target = browser.call("Target.createTarget", {"url": "about:blank"})["targetId"]
            session = browser.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
            browser.call("Emulation.setDeviceMetricsOverride",
                         {"width": 1180, "height": 600, "deviceScaleFactor": 1, "mobile": False}, session)
            browser.call("Page.navigate", {"url": url}, session)

            def js(expr):
                r = browser.call("Runtime.evaluate", {"expression": expr, "returnByValue": True}, session)
                return r["result"].get("value")
            return js, session

        js, page = tab(live["url"])

        def samples():
            return js("window.live ? window.live.samples : 0") or 0

        wait_for("the map to fill in", lambda: samples() >= 5, 180)

        # Another origin, in the same browser, knowing even the token.
        port = live["origin"].rsplit(":", 1)[1]
        evil, _ = tab(f"http://127.0.0.1:{serve_evil(EVIL.replace('TARGET', live['origin']).replace('TOKEN', live['token']))}/")
        attack = wait_for("the other origin's attempts", lambda: (evil("window.attack") or {}).get("done") and evil("window.attack"))
        for name in ("read_state", "read_state_token"):
            if attack[name].startswith("read"):
                raise RuntimeError(f"another origin read the scan ({name}): {attack[name]}")
        # A rebound name: the browser's Host is not the printed address.
        rebound, _ = tab(f"http://localhost:{port}/api/state?token={live['token']}")
        said = wait_for("the rebound page", lambda: rebound("document.body ? document.body.innerText : ''"))
        if "answers at" not in said:
            raise RuntimeError(f"a rebound name was answered: {said[:80]}")
        before = samples()
        wait_for("samples after the attacks", lambda: samples() > before)
        after_attack = state(live)["state"]["state"]
        if after_attack != "scanning":
            raise RuntimeError(f"another origin changed the scan: it is {after_attack}")

        # The page and `gonio pause|continue DIR` drive it.
        js("document.getElementById('pause').click()")
        wait_for("the page to say paused", lambda: js("window.live.state") == "paused")
        held = samples()
        time.sleep(1.5)
        if samples() != held:
            raise RuntimeError(f"{samples() - held} samples arrived while paused")
        if shot:
            png = browser.call("Page.captureScreenshot", {"format": "png"}, page)["data"]
            open(shot, "wb").write(base64.b64decode(png))
        subprocess.run([gonio, "continue", out], check=True, capture_output=True)
        wait_for("samples after `gonio continue`", lambda: samples() > held)
        subprocess.run([gonio, "pause", out], check=True, capture_output=True)
        wait_for("the page to say paused again", lambda: js("window.live.state") == "paused")
        held_again = samples()
        js("document.getElementById('continue').click()")
        wait_for("samples after the page's continue", lambda: samples() > held_again)
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
                          "held_at": [held, held_again], "drawn": samples(), "other_origin": attack,
                          "rebound": said[:60], "recoveries": outcome["recoveries"]}))
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
