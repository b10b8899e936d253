"""The fleet report and a per-bag report in a real browser (headless Chromium, driven over the
DevTools protocol on --remote-debugging-pipe): the page loads, every <img> has rendered
(complete, naturalWidth > 0), and there is no console error, uncaught exception or failed
resource load. Skipped where /usr/bin/chromium is missing (`./run test` installs it as root)."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
pytestmark = pytest.mark.skipif(not os.path.exists(CHROMIUM),
                                reason="headless Chromium not installed (apt-get install chromium)")
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--remote-debugging-pipe"]


class Cdp:
    """Minimal DevTools client over the pipe (fd 3: commands in, fd 4: messages out, each JSON
    text ending in a NUL byte)."""

    def __init__(self, user_dir: Path):
        cmd_r, self._cmd_w = os.pipe()
        self._out_r, out_w = os.pipe()
        # the child must see the two pipe ends as fds 3 and 4 (dup2'd fds are inheritable; the
        # others Python opens are not, so close_fds=False leaks nothing)
        def child():
            r, w = os.dup(cmd_r), os.dup(out_w)  # above 4 whatever the original numbers
            os.dup2(r, 3)
            os.dup2(w, 4)
        self.proc = subprocess.Popen([CHROMIUM, *FLAGS, f"--user-data-dir={user_dir}", "about:blank"],
                                     preexec_fn=child, close_fds=False,
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(cmd_r)
        os.close(out_w)
        self._buf = b""
        self._id = 0
        self.events: list[dict] = []

    def _read(self, deadline: float) -> dict:
        import select

        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._out_r], [], [], left)[0]:
                raise TimeoutError("no answer from Chromium")
            chunk = os.read(self._out_r, 1 << 16)
            if not chunk:
                raise RuntimeError("Chromium closed the pipe")
            self._buf += chunk
        msg, self._buf = self._buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method: str, params: dict | None = None, session: str | None = None, timeout=30.0):
        self._id += 1
        msg = {"id": self._id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self._cmd_w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read(deadline)
            if m.get("id") == self._id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def wait_event(self, method: str, timeout=30.0) -> dict:
        deadline = time.monotonic() + timeout
        for i, m in enumerate(self.events):
            if m.get("method") == method:
                return self.events.pop(i)
        while True:
            m = self._read(deadline)
            if m.get("method") == method:
                return m
            self.events.append(m)

    def close(self):
        try:
            self.call("Browser.close", timeout=5)
        except Exception:  # noqa: BLE001 - it is closing anyway
            pass
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
        os.close(self._cmd_w)
        os.close(self._out_r)


def check_page(path: Path, user_dir: Path) -> dict:
    """Load ``path``; return ``{"images": [(src, complete, naturalWidth)], "errors": [...]}``."""
    cdp = Cdp(user_dir)
    try:
        target = cdp.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        s = cdp.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for dom in ("Page", "Runtime", "Log"):
            cdp.call(f"{dom}.enable", session=s)
        cdp.call("Page.navigate", {"url": path.resolve().as_uri()}, session=s)
        cdp.wait_event("Page.loadEventFired", timeout=60)
        res = cdp.call("Runtime.evaluate", {"expression": "JSON.stringify(Array.from(document.images)"
                                            ".map(i => [i.getAttribute('src'), i.complete, i.naturalWidth]))",
                                            "returnByValue": True}, session=s)
        images = json.loads(res["result"]["value"])
        errors = []
        for m in cdp.events:
            p = m.get("params", {})
            if m.get("method") == "Runtime.exceptionThrown":
                errors.append(p["exceptionDetails"].get("text"))
            elif m.get("method") == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
                errors.append(str(p.get("args")))
            elif m.get("method") == "Log.entryAdded" and p["entry"]["level"] == "error":
                errors.append(p["entry"].get("text"))
        return {"images": images, "errors": errors}
    finally:
        cdp.close()


def test_checker_catches_broken_pages(tmp_path):
    """Control case: the checker itself sees a missing image and a console error."""
    (tmp_path / "p.html").write_text("<html><body><img src='missing.png'>"
                                     "<script>console.error('boom')</script></body></html>")
    res = check_page(tmp_path / "p.html", tmp_path / "ud")
    assert res["images"] == [["missing.png", True, 0]]
    assert any("boom" in e for e in res["errors"])


def test_fleet_and_bag_reports_render_in_chromium(tmp_path):
    from cablelab.plants.axis.fleet import write_fleet

    root, out = tmp_path / "fleet", tmp_path / "out"
    write_fleet(root, 2, 6, duration=4.0)
    p = subprocess.run([sys.executable, "-m", "cablelab.cli", "batch", str(root), "-o", str(out),
                        "--workers", "2", "--reports", "--json"], capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr[-3000:]
    index = out / "index.html"
    res = check_page(index, tmp_path / "ud1")
    assert len(res["images"]) >= 4
    assert all(c and w > 0 for _, c, w in res["images"]), res["images"]
    assert res["errors"] == []
    html = index.read_text()
    links = [line.split("href='")[1].split("'")[0] for line in html.split("<a ")[1:]
             if "href='bags/" in line]
    assert len(links) == 12
    bag_page = out / links[0]
    res = check_page(bag_page, tmp_path / "ud2")
    assert len(res["images"]) >= 3
    assert all(c and w > 0 for _, c, w in res["images"]), res["images"]
    assert res["errors"] == []
