#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The viewer's page in a real browser (headless Chromium, driven over the Chrome
DevTools Protocol with websocket-client): loads URL, reads the page's test hooks
(window.viewerStats: states received, frame, robots, landmarks and track arrows drawn,
transport)
twice, SECONDS apart, and saves a screenshot. Prints one JSON line:
{"transport", "rate" (states per second received between the looks), "frame0",
"frame1", "robots", "landmarks", "arrows" (tracks drawn), "errors" (script exceptions)}.

    browser_check.py URL --out SHOT.png [--seconds S] [--settle S]
        [--min-rate R] [--robots N] [--min-landmarks N] [--arrows N] [--advancing]
Exit 0 when every check given holds (and the page threw nothing), 1 otherwise, 77
when chromium is missing.
"""
import argparse
import base64
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
import urllib.request

import websocket  # websocket-client (tools/requirements.txt)


class Page:
    def __init__(self, ws_url):
        self.ws = websocket.create_connection(ws_url, timeout=30)
        self.next_id = 0
        self.errors = []

    def call(self, method, **params):
        self.next_id += 1
        self.ws.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            m = json.loads(self.ws.recv())
            if m.get("method") == "Runtime.exceptionThrown":
                self.errors.append(m["params"]["exceptionDetails"].get("text", "exception"))
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m["result"]

    def eval(self, expr):
        return self.call("Runtime.evaluate", expression=expr, returnByValue=True)["result"].get("value")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("url")
    ap.add_argument("--out", required=True)
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--settle", type=float, default=1.5, help="seconds after loading before the first look")
    ap.add_argument("--min-rate", type=float)
    ap.add_argument("--robots", type=int)
    ap.add_argument("--min-landmarks", type=int)
    ap.add_argument("--arrows", type=int, help="track arrows drawn (robots' and fused) at the second look")
    ap.add_argument("--advancing", action="store_true", help="the frame must advance between the looks")
    ap.add_argument("--window", default="1600,1000", help="the page's viewport, W,H")
    args = ap.parse_args()
    chromium = shutil.which("chromium")
    if not chromium:
        print("browser_check: no chromium", file=sys.stderr)
        return 77
    profile = tempfile.mkdtemp(prefix="browser_check_")
    proc = subprocess.Popen([chromium, "--headless=new", "--no-sandbox", "--disable-gpu", "--no-first-run",
                             "--remote-debugging-port=0", "--remote-debugging-address=127.0.0.1",
                             f"--user-data-dir={profile}", f"--window-size={args.window}", "about:blank"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = os.path.join(profile, "DevToolsActivePort")
        for _ in range(300):
            if os.path.exists(port_file) and open(port_file).read().count("\n") >= 1:
                break
            time.sleep(0.05)
        port = int(open(port_file).read().split("\n")[0])
        targets = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10))
        page = Page(next(t for t in targets if t["type"] == "page")["webSocketDebuggerUrl"])
        page.call("Runtime.enable")
        page.call("Page.enable")
        width, height = (int(v) for v in args.window.split(","))
        page.call("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1, mobile=False)
        page.call("Page.navigate", url=args.url)
        time.sleep(args.settle)
        look = "JSON.stringify(window.viewerStats || null)"
        s0 = json.loads(page.eval(look) or "null")
        time.sleep(args.seconds)
        s1 = json.loads(page.eval(look) or "null")
        shot = page.call("Page.captureScreenshot", format="png")
        with open(args.out, "wb") as f:
            f.write(base64.b64decode(shot["data"]))
        errors = page.errors
    finally:
        proc.kill()
        proc.wait()
        shutil.rmtree(profile, ignore_errors=True)
    if not s0 or not s1:
        print("browser_check: the page has no window.viewerStats")
        return 1
    result = {"transport": s1.get("transport"), "rate": round((s1["states"] - s0["states"]) / args.seconds, 1),
              "frame0": s0["frame"], "frame1": s1["frame"], "robots": s1["robots"], "landmarks": s1["landmarks"],
              "arrows": s1.get("arrows"), "errors": errors}
    print(json.dumps(result))
    bad = []
    if errors:
        bad.append(f"the page threw: {errors}")
    if args.min_rate is not None and result["rate"] < args.min_rate:
        bad.append(f"{result['rate']} states/s received, fewer than {args.min_rate}")
    if args.robots is not None and result["robots"] != args.robots:
        bad.append(f"{result['robots']} robots drawn, not {args.robots}")
    if args.min_landmarks is not None and result["landmarks"] < args.min_landmarks:
        bad.append(f"{result['landmarks']} landmarks drawn, fewer than {args.min_landmarks}")
    if args.arrows is not None and result["arrows"] != args.arrows:
        bad.append(f"{result['arrows']} track arrows drawn, not {args.arrows}")
    if args.advancing and not result["frame1"] > result["frame0"]:
        bad.append(f"the frame did not advance ({result['frame0']} -> {result['frame1']})")
    for b in bad:
        print("browser_check: FAIL " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
