#!/usr/bin/env python3
"""How fast the HTML page reacts, in headless Chromium over the DevTools protocol.

Owns the page benchmark of issue 24 (BENCHMARKS.md, "The HTML page at 20,000
leaves"): builds big maps and measures their pages as a reader meets them. Not
a test: it asserts nothing and prints figures. Python 3 standard library only
(its own small websocket client); needs Debian's `chromium`.

    python3 benches/page.py make [--bin target/release/nptreemap] [--out target/page-bench]
    python3 benches/page.py measure PAGE.html [PAGE.html ...] [--hovers 30] [--runs 3]
    python3 benches/page.py shots PAGE.html --out DIR [--query TEXT]

`make` writes three maps with their pages: `h20000`, a generated hierarchy of
20,000 leaves in three levels (benches/gen_similar.py, seed 1), `man-pages`,
this machine's English man pages of sections 1, 5, 7 and 8 (about 20,000;
benches/realdata/make.py's reader), and `c-headers`, a deep tree: the C
headers of /usr/include by folder, similar by the names they include; each
laid out by `nptreemap build`.

`measure` opens each page at 1280 x 900 and reports, per run (fresh tab):

- load: navigation start to the load event, to the first contentful paint and
  to the mark `nptreemap-ready` that the page's script sets when its handlers
  are attached; "interactive" is the latest of load, first paint and ready;
  and a first hover sent as soon as the page has loaded: when its feedback
  was painted (it waits for the map's own first raster);
- hover: the mouse moved onto a sample of leaf cells, one after another; for
  each, the Event Timing API's duration of the `pointerover` (input to the next
  paint, 8 ms resolution; Chromium reports none under 16 ms, counted as
  "< 16"), and input to the end of the next frame's main-thread work
  (requestAnimationFrame, then a task);
- focus: Tab through cells; the same two figures for each `keydown`;
- zoom: a click into a top-level group, input to the page's mark
  `nptreemap-zoomed` (labels placed for the zoomed extent);
- reach: for a sample of leaves, how many clicks from the overview show the
  leaf's label (its static label, or a zoom label `text[data-of]`).

`shots` writes PNG screenshots (desktop 1280 px and phone 390 px, light and
dark): the overview, zoomed twice, and a search for `--query`.
"""
from __future__ import annotations

import argparse
import base64
import datetime as dt
import json
import os
import platform
import random
import shutil
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from urllib.parse import quote

REPO = Path(__file__).resolve().parents[1]
DEADLINE = 120.0


# ---------------------------------------------------------------- websocket


class WebSocket:
    """A minimal RFC 6455 client: text frames out (masked), frames in."""

    def __init__(self, url: str):
        assert url.startswith("ws://"), url
        rest = url[len("ws://"):]
        host, _, path = rest.partition("/")
        name, _, port = host.partition(":")
        self.sock = socket.create_connection((name, int(port)), timeout=DEADLINE)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET /{path} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           "Sec-WebSocket-Version: 13\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(1)
            if not chunk:
                raise RuntimeError("websocket handshake: connection closed")
            head += chunk
        if b" 101 " not in head.split(b"\r\n", 1)[0]:
            raise RuntimeError(f"websocket handshake refused: {head!r}")

    def send(self, text: str) -> None:
        data = text.encode()
        mask = os.urandom(4)
        n = len(data)
        if n < 126:
            header = struct.pack("!BB", 0x81, 0x80 | n)
        elif n < 1 << 16:
            header = struct.pack("!BBH", 0x81, 0x80 | 126, n)
        else:
            header = struct.pack("!BBQ", 0x81, 0x80 | 127, n)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(data))
        self.sock.sendall(header + mask + masked)

    def _exact(self, n: int) -> bytes:
        buf = bytearray()
        while len(buf) < n:
            chunk = self.sock.recv(n - len(buf))
            if not chunk:
                raise RuntimeError("websocket closed")
            buf += chunk
        return bytes(buf)

    def recv(self) -> str:
        parts = []
        while True:
            b0, b1 = self._exact(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack("!H", self._exact(2))[0]
            elif n == 127:
                n = struct.unpack("!Q", self._exact(8))[0]
            payload = self._exact(n)
            opcode = b0 & 0x0F
            if opcode == 0x9:  # ping: answer, keep reading
                self.sock.sendall(struct.pack("!BB", 0x8A, 0x80) + b"\0\0\0\0")
                continue
            if opcode == 0x8:
                raise RuntimeError("websocket closed by the browser")
            parts.append(payload)
            if b0 & 0x80:
                return b"".join(parts).decode()


# ---------------------------------------------------------------- browser


class Browser:
    """Headless Chromium with one attached tab (flat session)."""

    def __init__(self, binary: str):
        self.profile = tempfile.mkdtemp(prefix="np-page-bench-")
        self.log = open(Path(self.profile) / "chromium.log", "w+")
        self.proc = subprocess.Popen(
            [binary, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--lang=en-US", "--remote-debugging-port=0", f"--user-data-dir={self.profile}/p",
             "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=self.log)
        url = None
        t0 = time.monotonic()
        while url is None:
            if time.monotonic() - t0 > DEADLINE:
                raise RuntimeError("chromium did not report its DevTools address")
            time.sleep(0.05)
            self.log.seek(0)
            for line in self.log.read().splitlines():
                if line.startswith("DevTools listening on "):
                    url = line.split(" on ", 1)[1].strip()
        self.ws = WebSocket(url)
        self.next = 0
        self.session = None
        self.events = []
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        self.session = self.call("Target.attachToTarget",
                                 {"targetId": target, "flatten": True})["sessionId"]

    def close(self):
        self.proc.kill()
        self.proc.wait()
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def call(self, method: str, params: dict | None = None) -> dict:
        self.next += 1
        message = {"id": self.next, "method": method, "params": params or {}}
        if self.session:
            message["sessionId"] = self.session
        self.ws.send(json.dumps(message))
        while True:
            reply = json.loads(self.ws.recv())
            if reply.get("id") == self.next:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            if "method" in reply:
                self.events.append(reply)

    def eval(self, expression: str):
        r = self.call("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                           "awaitPromise": True})
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression[:200]}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def wait(self, expression: str, what: str, limit: float | None = None):
        limit = DEADLINE if limit is None else limit
        t0 = time.monotonic()
        while True:
            v = self.eval(expression)
            if v:
                return v
            if time.monotonic() - t0 > limit:
                raise RuntimeError(f"timed out waiting for {what}")
            time.sleep(0.02)

    def try_wait(self, expression: str, what: str, limit: float):
        """`wait`, or None when the page does not answer in time (a busy
        renderer: the figure is then "more than `limit` s")."""
        try:
            return self.wait(expression, what, limit)
        except (RuntimeError, TimeoutError, OSError):
            return None

    def viewport(self, width: int, height: int, mobile: bool = False):
        self.call("Emulation.setDeviceMetricsOverride",
                  {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": mobile})

    def open(self, url: str):
        self.call("Page.navigate", {"url": url})
        self.wait(f"location.href === {json.dumps(url)} && document.readyState === 'complete'",
                  f"{url} to load")

    def mouse(self, x: float, y: float, kind: str = "mouseMoved", button: str = "none"):
        self.call("Input.dispatchMouseEvent",
                  {"type": kind, "x": x, "y": y, "button": button,
                   "buttons": 1 if button == "left" else 0, "clickCount": 1 if button == "left" else 0})

    def click(self, x: float, y: float):
        self.mouse(x, y)
        self.mouse(x, y, "mousePressed", "left")
        self.mouse(x, y, "mouseReleased", "left")

    def key(self, key: str, code: str, vk: int):
        for kind in ("keyDown", "keyUp"):
            self.call("Input.dispatchKeyEvent",
                      {"type": kind, "key": key, "code": code, "windowsVirtualKeyCode": vk})

    def screenshot(self, path: Path):
        data = self.call("Page.captureScreenshot", {"format": "png", "captureBeyondViewport": False})
        path.write_bytes(base64.b64decode(data["data"]))


def file_url(path: Path) -> str:
    return "file://" + quote(str(path.resolve()))


# Installed before every page's own scripts: Event Timing entries and, per
# input event, the time to the end of the next frame's main-thread work.
PROBE = r"""
window.__np = { events: [], frames: [] };
function npInMap(t) { return !!(t && t.closest && t.closest(".np-map")); }
new PerformanceObserver(function (list) {
  list.getEntries().forEach(function (e) {
    window.__np.events.push({ name: e.name, start: e.startTime, duration: e.duration, cell: npInMap(e.target),
                              processing: e.processingEnd - e.processingStart });
  });
}).observe({ type: "event", durationThreshold: 16, buffered: true });
["pointerover", "keydown", "click"].forEach(function (type) {
  window.addEventListener(type, function (e) {
    var t = e.timeStamp;
    if (!npInMap(e.target)) { return; }
    requestAnimationFrame(function () {
      setTimeout(function () { window.__np.frames.push({ name: type, start: t, ms: performance.now() - t }); }, 0);
    });
  }, true);
});
"""

# The page's leaves with a point on screen where the cell itself is hit.
LEAF_POINTS = r"""(function (count, seed) {
  var data = JSON.parse(document.querySelector(".np-data").textContent);
  var ids = data.nodes.map(function (n) { return n.id; });
  var at = new Map(ids.map(function (id, i) { return [id, i]; }));
  var isParent = new Set();
  data.nodes.forEach(function (n) {
    var p = n.parent;
    if (typeof p === "number") { isParent.add(p); }
    else if (typeof p === "string") { isParent.add(at.get(p)); }
  });
  var cells = new Map();
  document.querySelectorAll(".np-map svg path[data-id]").forEach(function (el) { cells.set(el.getAttribute("data-id"), el); });
  var leaves = [];
  for (var i = 0; i < ids.length; i++) { if (!isParent.has(i) && data.nodes[i].leaf !== false && cells.has(ids[i])) { leaves.push(i); } }
  var out = [], s = seed;
  for (var k = 0; k < leaves.length && out.length < count; k++) {
    s = (s * 1103515245 + 12345) % 2147483648;
    var el = cells.get(ids[leaves[s % leaves.length]]);
    var b = el.getBoundingClientRect();
    var x = Math.round(b.left + b.width / 2), y = Math.round(b.top + b.height / 2);
    if (x > 0 && y > 0 && x < innerWidth && y < innerHeight && document.elementFromPoint(x, y) === el) {
      out.push([el.getAttribute("data-id"), x, y]);
    }
  }
  return out;
})"""


def summary(values: list, unit: str = "ms") -> str:
    if not values:
        return "–"
    values = sorted(values)
    med = statistics.median(values)
    p90 = values[min(len(values) - 1, int(round(0.9 * (len(values) - 1))))]
    return f"median {med:.0f} {unit}, p90 {p90:.0f}, max {values[-1]:.0f} (n={len(values)})"


def timing_summary(durations: list, count: int) -> str:
    """Event Timing durations of `count` inputs: entries exist only from 16 ms
    on, so the inputs without one painted sooner."""
    under = max(0, count - len(durations))
    text = f"{under} of {count} under 16 ms"
    if durations:
        text += f"; the others {summary(durations)}"
    return text


def measure_page(browser: Browser, path: Path, args) -> dict:
    url = file_url(path)
    browser.viewport(1280, 900)
    browser.call("Page.enable")
    browser.call("Page.addScriptToEvaluateOnNewDocument", {"source": PROBE})
    runs = []
    for run in range(args.runs):
        browser.open("about:blank")
        browser.open(url)
        load = browser.eval("""(function () {
          var nav = performance.getEntriesByType("navigation")[0];
          var fcp = performance.getEntriesByName("first-contentful-paint")[0];
          var ready = performance.getEntriesByName("nptreemap-ready")[0];
          return { load: nav.loadEventEnd, dcl: nav.domContentLoadedEventEnd,
                   fcp: fcp ? fcp.startTime : null, ready: ready ? ready.startTime : null };
        })()""")
        # The first hover, at once: its feedback can show only once the map
        # itself is painted, so its paint time is when the page answers.
        points = browser.eval(f"{LEAF_POINTS}({args.hovers + 1}, {run + 1})")
        first = None
        if points:
            browser.mouse(points[0][1], points[0][2])
            first = browser.try_wait("""(function () {
              var e = window.__np.events.filter(function (e) { return e.name === "pointerover"; })[0];
              var f = window.__np.frames.filter(function (f) { return f.name === "pointerover"; })[0];
              if (e) { return { start: e.start, painted: e.start + e.duration }; }
              // Event Timing reports a paint 16 ms or more after its input,
              // once painted; none a second after the frame: under 16 ms.
              if (f && performance.now() - (f.start + f.ms) > 1000) { return { start: f.start, painted: f.start + 16 }; }
              return null;
            })()""", "the first hover", args.deadline)
            points = points[1:]
            time.sleep(1.0)
        load["first_hover"] = first
        if points and first is None:
            # The page did not answer its first hover in time: nothing more
            # to time on it.
            runs.append({"load": load, "hover_timing": [], "hover_frames": [], "hovers": 0,
                         "focus_timing": [], "focus_frames": [], "tabs": 0, "stuck": args.deadline})
            break
        browser.eval("window.__np.events = []; window.__np.frames = []; 0")
        for _, x, y in points:
            browser.mouse(x, y)
            time.sleep(args.pause)
        browser.mouse(1, 1)
        time.sleep(0.5)
        hover = browser.eval("window.__np")
        focus = {"events": [], "frames": []}
        tabs = 0
        if args.hovers:
            # Focus: Tab until a cell has focus, then through cells.
            browser.eval("window.__np.events = []; window.__np.frames = []; document.activeElement && document.activeElement.blur(); 0")
            for _ in range(8):
                browser.key("Tab", "Tab", 9)
                if browser.eval("!!(document.activeElement && document.activeElement.matches('path[data-id]'))"):
                    break
            browser.eval("window.__np.events = []; window.__np.frames = []; 0")
            for _ in range(args.hovers):
                browser.key("Tab", "Tab", 9)
                tabs += 1
                time.sleep(args.pause)
            focus = browser.eval("window.__np")
            browser.eval("document.activeElement && document.activeElement.blur(); 0")
        runs.append({
            "load": load,
            "hover_timing": [e["duration"] for e in hover["events"] if e["name"] == "pointerover" and e["cell"]],
            "hover_frames": [f["ms"] for f in hover["frames"] if f["name"] == "pointerover"],
            "hovers": len(points),
            "focus_timing": [e["duration"] for e in focus["events"] if e["name"] == "keydown" and e["cell"]],
            "focus_frames": [f["ms"] for f in focus["frames"] if f["name"] == "keydown"],
            "tabs": tabs,
        })
    result = {"page": str(path), "bytes": path.stat().st_size, "runs": runs}
    if args.reach and not any(run.get("stuck") for run in runs):
        result.update(zoom_and_reach(browser, url, args))
    return result


def zoom_and_reach(browser: Browser, url: str, args) -> dict:
    """Zoom time into a top-level group, and clicks needed to show a leaf's label."""
    browser.open(url)
    if not browser.eval("!!document.querySelector('.np-data') && !!performance.getEntriesByName('nptreemap-ready')[0]"):
        return {}
    leaves = browser.eval(f"{LEAF_POINTS}({args.reach}, 7)")
    clicks, zoom_ms = [], []
    for leaf_id, _, _ in leaves:
        browser.open("about:blank")
        browser.open(url)
        n = 0
        while n <= 6:
            shown = browser.eval(f"""(function (id) {{
              var data = JSON.parse(document.querySelector(".np-data").textContent);
              var zoomed = document.querySelector(".nptreemap").classList.contains("np-zoomed");
              if (zoomed) {{
                return Array.prototype.some.call(document.querySelectorAll(".np-map text[data-of]"),
                  function (t) {{ return t.getAttribute("data-of") === id; }});
              }}
              var placed = (data.labels && data.labels.placed) || [];
              return placed.some(function (i) {{ return data.nodes[i].id === id; }});
            }})({json.dumps(leaf_id)})""")
            if shown:
                break
            point = browser.eval(f"""(function (id) {{
              var el = Array.prototype.find.call(document.querySelectorAll(".np-map svg path[data-id]"),
                function (e) {{ return e.getAttribute("data-id") === id; }});
              var d = el.getAttribute("d").match(/-?[0-9.]+/g).map(Number);
              var m = el.getScreenCTM(), cx = 0, cy = 0, k = d.length / 2;
              for (var i = 0; i < d.length; i += 2) {{ cx += d[i] / k; cy += d[i + 1] / k; }}
              var pts = [[cx, cy]];
              for (var i = 0; i < d.length; i += 2) {{ pts.push([(cx + d[i]) / 2, (cy + d[i + 1]) / 2]); }}
              for (var j = 0; j < pts.length; j++) {{
                var p = new DOMPoint(pts[j][0], pts[j][1]).matrixTransform(m);
                var x = Math.round(p.x), y = Math.round(p.y);
                if (x > 0 && y > 0 && x < innerWidth && y < innerHeight && document.elementFromPoint(x, y) === el) {{ return [x, y]; }}
              }}
              return null;
            }})({json.dumps(leaf_id)})""")
            if not point:
                n = None
                break
            marks = browser.eval("performance.getEntriesByName('nptreemap-zoomed').length")
            t0 = browser.eval("performance.now()")
            browser.click(point[0], point[1])
            n += 1
            try:
                browser.wait(f"performance.getEntriesByName('nptreemap-zoomed').length > {marks}", "zoom", 30)
            except RuntimeError:
                n = None
                break
            zoom_ms.append(browser.eval(f"performance.getEntriesByName('nptreemap-zoomed')[{marks}].startTime") - t0)
            browser.mouse(1, 1)
        clicks.append(n)
    return {"reach": clicks, "zoom_ms": zoom_ms}


def report(results: list, args) -> str:
    lines = []
    now = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    cpu = ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    version = subprocess.run([args.chromium, "--version"], capture_output=True, text=True).stdout.strip()
    lines.append(f"{now}; {os.cpu_count()} cores ({cpu}), load average "
                 f"{', '.join(f'{x:.1f}' for x in os.getloadavg())}; {version}; {platform.system()}")
    lines.append(f"command: python3 benches/page.py measure {' '.join(str(r['page']) for r in results)} "
                 f"--runs {args.runs} --hovers {args.hovers} --reach {args.reach}")
    lines.append("")
    for r in results:
        lines.append(f"### {Path(r['page']).name} ({r['bytes'] / 1e6:.1f} MB)")
        inter = []
        first_hover = []
        for k, run in enumerate(r["runs"]):
            ld = run["load"]
            marks = [v for v in (ld["load"], ld["fcp"], ld["ready"]) if v is not None]
            inter.append(max(marks))
            fh = ld.get("first_hover")
            if fh:
                first_hover.append(fh["painted"])
            if run.get("stuck"):
                lines.append(f"- run {k + 1}: load event {ld['load']:.0f} ms, first paint "
                             f"{(ld['fcp'] or 0):.0f} ms; the first hover was not painted within "
                             f"{run['stuck']:.0f} s (the page stopped answering; later runs skipped)")
                continue
            lines.append(f"- run {k + 1}: load event {ld['load']:.0f} ms, first paint "
                         f"{(ld['fcp'] or 0):.0f} ms, script ready "
                         f"{'–' if ld['ready'] is None else '%.0f ms' % ld['ready']}; "
                         f"interactive {max(marks):.0f} ms; the first hover (sent at "
                         f"{'–' if not fh else '%.0f ms' % fh['start']}) painted at "
                         f"{'–' if not fh else '%.0f ms' % fh['painted']}")
        hov_t = [d for run in r["runs"] for d in run["hover_timing"]]
        hov_f = [d for run in r["runs"] for d in run["hover_frames"]]
        foc_t = [d for run in r["runs"] for d in run["focus_timing"]]
        foc_f = [d for run in r["runs"] for d in run["focus_frames"]]
        lines.append(f"- interactive (latest of load event, first paint, script ready): {summary(inter)}")
        lines.append(f"- first hover's feedback painted, from navigation start: {summary(first_hover)}")
        lines.append(f"- hover, input to next paint (Event Timing): "
                     f"{timing_summary(hov_t, sum(run['hovers'] for run in r['runs']))}")
        lines.append(f"- hover, input to end of next frame (main thread): {summary(hov_f)}")
        lines.append(f"- focus (Tab), input to next paint (Event Timing): "
                     f"{timing_summary(foc_t, sum(run['tabs'] for run in r['runs']))}")
        lines.append(f"- focus (Tab), input to end of next frame (main thread): {summary(foc_f)}")
        if r.get("zoom_ms"):
            lines.append(f"- zoom, click to labels placed: {summary(r['zoom_ms'])}")
        if r.get("reach"):
            done = [c for c in r["reach"] if c is not None]
            hist = {c: done.count(c) for c in sorted(set(done))}
            lines.append(f"- clicks until a leaf's label shows ({len(r['reach'])} sampled leaves): "
                         + ", ".join(f"{c}: {n}" for c, n in hist.items())
                         + (f"; not reached: {len(r['reach']) - len(done)}" if len(done) < len(r["reach"]) else ""))
        lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------- screenshots

SHOT_ZOOM = r"""(function () {
  // The centre of the biggest cell inside the current view that is hit.
  var svg = document.querySelector(".np-map svg");
  var best = null, area = 0;
  document.querySelectorAll(".np-map svg path[data-id]").forEach(function (el) {
    var b = el.getBoundingClientRect();
    var x = Math.round(b.left + b.width / 2), y = Math.round(b.top + b.height / 2);
    if (b.width * b.height > area && x > 0 && y > 0 && x < innerWidth && y < innerHeight &&
        document.elementFromPoint(x, y) === el) { best = [x, y]; area = b.width * b.height; }
  });
  return best;
})()"""


def shots(args):
    browser = Browser(args.chromium)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    try:
        for page in args.pages:
            url = file_url(Path(page))
            stem = Path(page).stem
            for width, height, mobile, name in ((1280, 900, False, "desktop"), (390, 844, True, "phone")):
                for scheme in ("light", "dark"):
                    browser.viewport(width, height, mobile)
                    browser.call("Emulation.setEmulatedMedia",
                                 {"features": [{"name": "prefers-color-scheme", "value": scheme}]})
                    browser.open(url)
                    browser.screenshot(out / f"{stem}-{name}-{scheme}-overview.png")
                    for k in (1, 2):
                        at = browser.eval(SHOT_ZOOM)
                        if at:
                            marks = browser.eval("performance.getEntriesByName('nptreemap-zoomed').length")
                            browser.click(at[0], at[1])
                            try:
                                browser.wait(f"performance.getEntriesByName('nptreemap-zoomed').length > {marks}", "zoom", 30)
                            except RuntimeError:
                                pass
                            browser.mouse(1, 1)
                            time.sleep(0.5)
                        browser.screenshot(out / f"{stem}-{name}-{scheme}-zoom{k}.png")
                    if args.query:
                        browser.open(url)
                        browser.eval("document.querySelector('.np-search-box').focus(); 0")
                        browser.call("Input.insertText", {"text": args.query})
                        time.sleep(0.5)
                        browser.screenshot(out / f"{stem}-{name}-{scheme}-search-list.png")
                        browser.key("Enter", "Enter", 13)
                        time.sleep(1.5)
                        browser.screenshot(out / f"{stem}-{name}-{scheme}-searched.png")
                        # The found cell up close, twice as large.
                        box = browser.eval("""(function () {
                          var id = document.querySelector(".nptreemap").getAttribute("data-found");
                          var el = Array.prototype.find.call(document.querySelectorAll(".np-map svg path[data-id]"),
                            function (e) { return e.getAttribute("data-id") === id; });
                          if (!el) { return null; }
                          var r = el.getBoundingClientRect();
                          return [Math.max(0, r.left - 60), Math.max(0, r.top - 60), r.width + 120, r.height + 120];
                        })()""")
                        if box:
                            clip = {"x": box[0], "y": box[1], "width": box[2], "height": box[3], "scale": 2}
                            data = browser.call("Page.captureScreenshot", {"format": "png", "clip": clip})
                            (out / f"{stem}-{name}-{scheme}-found.png").write_bytes(base64.b64decode(data["data"]))
            print(f"screenshots of {page} in {out}")
    finally:
        browser.close()


# ---------------------------------------------------------------- maps


INCLUDE = __import__("re").compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', __import__("re").M)


def c_headers(folder: Path, top: Path = Path("/usr/include"), dim: int = 32) -> int:
    """A deep tree: the C headers under `top` by folder, sized by bytes,
    similar by the names they include (hashed into `dim` dimensions, cosine)."""
    import zlib
    root = {"id": str(top), "name": top.name, "similarityMeasure": "cosine", "children": []}
    nodes = {top: root}
    leaves = 0
    for path in sorted(top.rglob("*.h")):
        if not path.is_file():
            continue
        text = path.read_text(encoding="utf-8", errors="replace")
        vec = [0.0] * dim
        for name in INCLUDE.findall(text):
            vec[zlib.crc32(name.encode()) % dim] += 1.0
        norm = sum(x * x for x in vec) ** 0.5 or 1.0
        parent = top
        for part in path.relative_to(top).parent.parts:
            child = parent / part
            if child not in nodes:
                node = {"id": str(child.relative_to(top)), "name": part, "children": []}
                nodes[parent]["children"].append(node)
                nodes[child] = node
            parent = child
        nodes[parent]["children"].append({
            "id": str(path.relative_to(top)), "name": path.name, "weight": len(text.encode()),
            "embeddings": [round(x / norm, 4) for x in vec]})
        leaves += 1
    (folder / "c-headers.json").write_text(json.dumps(root), encoding="utf-8")
    return leaves


def make(args):
    out = Path(args.out)
    gen = out / "h20000"
    man = out / "man-pages"
    gen.mkdir(parents=True, exist_ok=True)
    man.mkdir(parents=True, exist_ok=True)
    if not (gen / "h20000.json").exists():
        subprocess.run([sys.executable, str(REPO / "benches" / "gen_similar.py"), "--n", "20000",
                        "--depth", "3", "--dim", "64", "--seed", "1", "--out", str(gen / "h20000.json")],
                       check=True)
    (gen / "nptreemap.yaml").write_text(
        "# 20,000 generated leaves in three levels (benches/page.py make)\n"
        "render:\n  labels: {unit: \" KiB\"}\n"
        "datasets:\n  - name: h20000\n"
        "    title: Generated hierarchy of 20,000 leaves in three levels\n"
        "    format: hierarchy-json\n    files: {hierarchy: h20000.json}\n"
        "    outputs: [out/h20000.html, out/h20000.json]\n", encoding="utf-8")
    if not (man / "pages.csv").exists():
        sys.path.insert(0, str(REPO / "benches" / "realdata"))
        import make as realdata  # noqa: E402  (the real-data corpus's readers)
        facts = realdata.make_man_pages(man, sections=("1", "5", "7", "8"))
        print(f"man-pages: {facts['leaves']} pages")
    (man / "nptreemap.yaml").write_text(
        "# This machine's English man pages of sections 1, 5, 7 and 8 (benches/page.py make)\n"
        "render:\n  labels: {unit: \" B\"}\n"
        "datasets:\n  - name: man-pages\n"
        "    title: Man pages by size; neighbours have similar text\n"
        "    format: embedding-matrix\n"
        "    files: {nodes: pages.csv, vectors: vectors-resolved.tsv}\n"
        "    fields: {weight: bytes, groups: [section, package]}\n"
        "    outputs: [out/man-pages.html, out/man-pages.json]\n", encoding="utf-8")
    heads = out / "c-headers"
    heads.mkdir(parents=True, exist_ok=True)
    if not (heads / "c-headers.json").exists():
        print(f"c-headers: {c_headers(heads)} headers")
    (heads / "nptreemap.yaml").write_text(
        "# This machine's C headers (/usr/include) by folder (benches/page.py make)\n"
        "render:\n  labels: {unit: \" B\"}\n"
        "datasets:\n  - name: c-headers\n"
        "    title: C headers by size; neighbours include alike\n"
        "    format: hierarchy-json\n    files: {hierarchy: c-headers.json}\n"
        "    outputs: [out/c-headers.html, out/c-headers.json]\n", encoding="utf-8")
    for folder in (gen, man, heads):
        t0 = time.monotonic()
        subprocess.run([args.bin, "build", str(folder / "nptreemap.yaml")], check=True)
        print(f"{folder.name}: built in {time.monotonic() - t0:.0f} s")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--chromium", default=shutil.which("chromium") or "/usr/bin/chromium")
    sub = ap.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make", help="build the 20,000-leaf maps and the deep C-headers map")
    m.add_argument("--bin", default=str(REPO / "target" / "release" / "nptreemap"))
    m.add_argument("--out", default=str(REPO / "target" / "page-bench"))
    s = sub.add_parser("measure", help="measure pages")
    s.add_argument("pages", nargs="+")
    s.add_argument("--runs", type=int, default=3)
    s.add_argument("--hovers", type=int, default=30)
    s.add_argument("--reach", type=int, default=20, help="leaves sampled for the clicks to their label")
    s.add_argument("--pause", type=float, default=0.25, help="seconds between interactions")
    s.add_argument("--json", help="also write the raw figures here")
    s.add_argument("--deadline", type=float, default=60.0,
                   help="seconds to wait for the first hover's paint before giving up")
    t = sub.add_parser("shots", help="screenshots of pages")
    t.add_argument("pages", nargs="+")
    t.add_argument("--out", required=True)
    t.add_argument("--query", default="")
    args = ap.parse_args()
    global DEADLINE
    # A busy renderer answers late: every read waits longer than any wait.
    DEADLINE = max(DEADLINE, getattr(args, "deadline", 0) + 60)
    if args.command == "make":
        make(args)
        return 0
    if args.command == "shots":
        shots(args)
        return 0
    browser = Browser(args.chromium)
    try:
        results = [measure_page(browser, Path(p), args) for p in args.pages]
    finally:
        browser.close()
    text = report(results, args)
    print(text)
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
