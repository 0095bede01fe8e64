#!/usr/bin/env python3
"""The HTML report in headless Chromium (Debian's chromium + chromium-driver, WebDriver over
HTTP with the standard library only).

    html_report_test.py KUAVO WORKDIR            the test (ctest): exit 0 pass, 1 fail, 77 skip
    html_report_test.py --measure REPORT_DIR     open a report, print its load time (no checks)

The test makes a short report with `kuavo simulate` + `kuavo replay`: 4 steps in place, and the
same with a sideways push that throws the robot over; then, from disk:
  - no console errors (the page also checks its forward kinematics against the model's);
  - the 3D view renders: screenshots at two timeline positions differ, and hiding the robot
    changes a robot-sized patch of pixels inside the view (the robot is in view); hiding the
    human skeleton (the built-in dance's keypoints) changes pixels too;
  - clicking on the timeline moves the replay's time, the robot and the plots' cursor;
  - the falling run shows the fall on the timeline (at the summary's time, drawn red), the
    other run shows none.
Skipped (77) when chromium or chromedriver is not installed (tools/run.sh installs them).
"""
import base64
import json
import os
import shutil
import socket
import struct
import subprocess
import sys
import time
import urllib.error
import urllib.request
import zlib

SKIP = 77
# Pixels that differ by more than this (max over RGB, 0..255) count as changed: above
# SwiftShader's anti-aliasing noise between two renders of the same scene (0..2).
PIXEL_TOLERANCE = 24
# The robot is ~1.3 m tall at 3 m from the camera: it covers several percent of the view;
# 1 % is well above noise and fails for an empty or robot-less scene.
MIN_ROBOT_SHARE = 0.01
# Two timeline positions 2 s apart in a stepping run change at least this share of the view.
MIN_CHANGED_SHARE = 0.002


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


# ---- PNG (8-bit RGB/RGBA, non-interlaced: what Chromium's screenshots are) -------------
def decode_png(data):
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or color not in (2, 6) or interlace:
                raise ValueError("unsupported PNG: depth %d colour %d interlace %d" % (depth, color, interlace))
            bpp = 4 if color == 6 else 3
        elif kind == b"IDAT":
            idat += body
    raw = zlib.decompress(idat)
    stride = width * bpp
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return width, height, bpp, rows


def changed_pixels(img_a, img_b):
    """(count, bounding box) of pixels whose RGB differ by more than PIXEL_TOLERANCE."""
    wa, ha, bpp, ra = img_a
    wb, hb, _, rb = img_b
    if (wa, ha) != (wb, hb):
        fail("screenshots of different sizes: %dx%d, %dx%d" % (wa, ha, wb, hb))
    n, box = 0, [wa, ha, -1, -1]
    for y in range(ha):
        la, lb = ra[y], rb[y]
        if la == lb:
            continue
        for x in range(wa):
            i = x * bpp
            if max(abs(la[i] - lb[i]), abs(la[i + 1] - lb[i + 1]), abs(la[i + 2] - lb[i + 2])) > PIXEL_TOLERANCE:
                n += 1
                box = [min(box[0], x), min(box[1], y), max(box[2], x), max(box[3], y)]
    return n, box


# ---- WebDriver ------------------------------------------------------------------------------
class Driver:
    def __init__(self, chromedriver, chromium):
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        self.port = s.getsockname()[1]
        s.close()
        self.proc = subprocess.Popen([chromedriver, "--port=%d" % self.port], stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
        for _ in range(100):
            try:
                if self.call("GET", "/status")["value"].get("ready"):
                    break
            except (urllib.error.URLError, ConnectionError):
                time.sleep(0.1)
        else:
            raise RuntimeError("chromedriver did not start")
        caps = {"capabilities": {"alwaysMatch": {
            "browserName": "chrome",
            "goog:loggingPrefs": {"browser": "ALL"},
            "goog:chromeOptions": {"binary": chromium, "args": [
                "--headless=new", "--no-sandbox", "--window-size=1400,1000", "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader", "--allow-file-access-from-files", "--disable-dev-shm-usage"]}}}}
        self.session = self.call("POST", "/session", caps)["value"]["sessionId"]

    def call(self, method, path, body=None):
        req = urllib.request.Request("http://127.0.0.1:%d%s" % (self.port, path), method=method,
                                     data=None if body is None else json.dumps(body).encode(),
                                     headers={"Content-Type": "application/json"})
        try:
            with urllib.request.urlopen(req, timeout=120) as r:
                return json.loads(r.read())
        except urllib.error.HTTPError as e:
            raise RuntimeError("WebDriver %s %s: %s" % (method, path, e.read()[:400]))

    def s(self, method, path, body=None):
        return self.call(method, "/session/%s%s" % (self.session, path), body)["value"]

    def js(self, script, *args):
        return self.s("POST", "/execute/sync", {"script": script, "args": list(args)})

    def js_async(self, script, *args):
        return self.s("POST", "/execute/async", {"script": script, "args": list(args)})

    def element(self, css):
        return list(self.s("POST", "/element", {"using": "css selector", "value": css}).values())[0]

    def shot(self, css):
        return decode_png(base64.b64decode(self.s("GET", "/element/%s/screenshot" % self.element(css))))

    def click_at(self, css, fraction_x):
        """A real pointer click at fraction_x of the element's width, mid-height."""
        el = self.element(css)
        rect = self.s("GET", "/element/%s/rect" % el)
        x = int(rect["width"] * (fraction_x - 0.5))
        origin = {"element-6066-11e4-a52e-4f735466cecf": el}
        self.s("POST", "/actions", {"actions": [{"type": "pointer", "id": "mouse", "parameters": {"pointerType": "mouse"},
                                                 "actions": [{"type": "pointerMove", "origin": origin, "x": x, "y": 0},
                                                             {"type": "pointerDown", "button": 0},
                                                             {"type": "pointerUp", "button": 0}]}]})

    def console(self):
        for path in ("/se/log", "/log"):
            try:
                return self.s("POST", path, {"type": "browser"})
            except RuntimeError:
                continue
        fail("chromedriver returns no browser log")

    def quit(self):
        try:
            self.s("DELETE", "")
        finally:
            self.proc.terminate()
            self.proc.wait(timeout=20)


def open_report(d, index_html):
    d.s("POST", "/url", {"url": "file://" + os.path.abspath(index_html)})
    for _ in range(600):
        if d.js("return !!(window.KUAVO_VIEW && window.KUAVO_VIEW.ready);"):
            return d.js("return window.KUAVO_VIEW.ready_ms;")
        time.sleep(0.05)
    fail("the page never became ready (console: %s)" % d.console())


def seek(d, t_s):
    d.js("window.KUAVO_VIEW.seek(arguments[0]);", t_s)
    return d.js("return window.KUAVO_VIEW.state();")


def find_browser():
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    chromedriver = shutil.which("chromedriver")
    if not chromium or not chromedriver:
        print("SKIP: chromium or chromedriver not installed (tools/run.sh installs them)")
        sys.exit(SKIP)
    return chromium, chromedriver


def run(cmd):
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        fail("%s exited %d:\n%s" % (" ".join(cmd), r.returncode, r.stdout[-2000:]))


def measure(report_dir):
    chromium, chromedriver = find_browser()
    d = Driver(chromedriver, chromium)
    try:
        t0 = time.monotonic()
        ready_ms = open_report(d, os.path.join(report_dir, "index.html"))
        since_navigation_ms = d.js("return window.KUAVO_VIEW.load_ms;")
        print("ready (first frame drawn) %.0f ms after navigation start (%.0f ms in app.js); %.0f ms wall "
              "from the WebDriver navigation request" % (since_navigation_ms, ready_ms, 1000 * (time.monotonic() - t0)))
        print("console:", [e["message"][:200] for e in d.console() if e["level"] == "SEVERE"])
    finally:
        d.quit()


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--measure":
        return measure(sys.argv[2])
    if len(sys.argv) != 3:
        print(__doc__)
        return 2
    kuavo, work = sys.argv[1], sys.argv[2]
    chromium, chromedriver = find_browser()
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    ok, fall = os.path.join(work, "steps.csv"), os.path.join(work, "steps_pushed.csv")
    run([kuavo, "simulate", "--step-in-place", "4", "--log", ok, "--summary", ok[:-4] + ".json"])
    # 60 N·s sideways at 2 s: far beyond what a stepping robot can catch.
    run([kuavo, "simulate", "--step-in-place", "4", "--push", "2:0,600,0:0.1", "--log", fall,
         "--summary", fall[:-4] + ".json"])
    summary = json.load(open(fall[:-4] + ".json"))
    if not summary["fell"]:
        fail("the pushed run did not fall: the fall check would test nothing")
    if json.load(open(ok[:-4] + ".json"))["fell"]:
        fail("the unpushed run fell")
    # The built-in dance's human keypoints (geometric stage: a second), drawn beside the robot.
    human = os.path.join(work, "human.csv")
    run([kuavo, "retarget", "-o", os.path.join(work, "dance.motion"), "--report", os.path.join(work, "r.json"),
         "--stage", "geometric", "--human-csv", human])
    report = os.path.join(work, "report")
    run([kuavo, "replay", ok, fall, "--out", report, "--human", human])

    d = Driver(chromedriver, chromium)
    try:
        ready_ms = open_report(d, os.path.join(report, "index.html"))
        print("report ready in %.0f ms" % ready_ms)
        duration = d.js("return KUAVO.report.runs[0].duration_s;")

        # The 3D view renders and moves with the timeline.
        s1 = seek(d, 0.3 * duration)
        a = d.shot("#view3d canvas")
        s2 = seek(d, 0.3 * duration + 2.0)
        b = d.shot("#view3d canvas")
        n, _ = changed_pixels(a, b)
        share = n / (a[0] * a[1])
        print("two timeline positions: %.2f %% of the view changed" % (100 * share))
        if share < MIN_CHANGED_SHARE:
            fail("the 3D view is the same at %.2f s and %.2f s" % (s1["t_s"], s2["t_s"]))
        d.s("POST", "/element/%s/click" % d.element("#show-robot"), {})
        c = d.shot("#view3d canvas")
        d.s("POST", "/element/%s/click" % d.element("#show-robot"), {})
        n, box = changed_pixels(b, c)
        share = n / (b[0] * b[1])
        print("robot: %.2f %% of the view, box %s in %dx%d" % (100 * share, box, b[0], b[1]))
        if share < MIN_ROBOT_SHARE:
            fail("hiding the robot changes %.3f %% of the view: no robot in view" % (100 * share))
        if box[0] <= 0 and box[2] >= b[0] - 1 and box[1] <= 0 and box[3] >= b[1] - 1:
            fail("hiding the robot changes the whole view: not a robot but the scene")

        # The human skeleton is drawn (beside the robot by default) and can be hidden.
        d.js("document.getElementById('human-mode').value = 'off'; document.getElementById('human-mode')"
             ".dispatchEvent(new Event('change'));")
        e = d.shot("#view3d canvas")
        d.js("document.getElementById('human-mode').value = 'beside'; document.getElementById('human-mode')"
             ".dispatchEvent(new Event('change'));")
        n, box = changed_pixels(b, e)
        print("human skeleton: %d pixels, box %s" % (n, box))
        if n < 200:
            fail("hiding the human skeleton changes %d pixels: no skeleton drawn" % n)

        # Clicking on the timeline moves the time, the robot and the plots' cursor.
        d.click_at("#scrub", 0.2)
        p = d.js("return window.KUAVO_VIEW.state();")
        view_p, plot_p = d.shot("#view3d canvas"), d.shot("#plot-tracking")
        d.click_at("#scrub", 0.8)
        q = d.js("return window.KUAVO_VIEW.state();")
        view_q, plot_q = d.shot("#view3d canvas"), d.shot("#plot-tracking")
        print("timeline clicks: t %.2f -> %.2f s, cursors %s -> %s" % (p["t_s"], q["t_s"], p["cursor_px"], q["cursor_px"]))
        if not (abs(p["t_s"] - 0.2 * duration) < 0.05 * duration and abs(q["t_s"] - 0.8 * duration) < 0.05 * duration):
            fail("clicks at 20 %% and 80 %% of the timeline gave t = %.2f, %.2f s of %.2f" % (p["t_s"], q["t_s"], duration))
        if changed_pixels(view_p, view_q)[0] < MIN_CHANGED_SHARE * view_p[0] * view_p[1]:
            fail("scrubbing did not move the robot")
        if not all(cq > cp + 10 for cp, cq in zip(p["cursor_px"], q["cursor_px"])) or len(p["cursor_px"]) != 4:
            fail("scrubbing did not move every plot's cursor: %s -> %s" % (p["cursor_px"], q["cursor_px"]))
        if changed_pixels(plot_p, plot_q)[0] < 20:
            fail("the tracking plot's pixels did not change when scrubbing")
        if d.js("return document.querySelectorAll('.mark-fall').length;") != 0:
            fail("a run that did not fall shows a fall")

        # The falling run: the fall on the timeline, where the summary says, in red.
        d.js_async("window.KUAVO_VIEW.selectRun(1, arguments[0]);")
        marks = d.js("return Array.from(document.querySelectorAll('.mark-fall')).map(e => Number(e.dataset.start_s));")
        fall_duration = d.js("return KUAVO.report.runs[1].duration_s;")
        if len(marks) != 1 or abs(marks[0] - summary["fell_at_s"]) > 1e-3:
            fail("the fall at %.3f s is marked at %s" % (summary["fell_at_s"], marks))
        seek(d, 0.0)
        w, h, bpp, rows = d.shot("#timeline")
        x = min(w - 1, int(w * summary["fell_at_s"] / fall_duration) + 1)
        red = [rows[y][x * bpp:x * bpp + 3] for y in range(h // 4, 3 * h // 4)]
        if not any(r[0] > 180 and r[1] < 90 and r[2] < 90 for r in red):
            fail("no red fall mark at x = %d of the timeline (fell at %.2f s of %.2f)" % (x, summary["fell_at_s"], fall_duration))
        print("fall marked at %.3f s" % marks[0])

        severe = [e["message"] for e in d.console() if e["level"] == "SEVERE"]
        if severe:
            fail("console errors: %s" % severe)
        if not d.js("return window.KUAVO_VIEW.state().fk_error_m < 1e-4;"):
            fail("the page's forward kinematics disagree with the model")
    finally:
        d.quit()
    print("PASS")
    return 0


if __name__ == "__main__":
    sys.exit(main())
