"""The viewer's web page in a real browser: headless Chromium loads the page that
`scripts/web.sh` built from a server on 127.0.0.1, runs the flexion preset to 1.0 s of
simulated time, reads the knee angle through the page's hooks (`window.myoslice`) and
screenshots the canvas; a corrupt NIfTI opened in the page gives an error there and the
leg keeps running.

Needs `chromium` on the PATH, the built page (MYOSLICE_WEB_DIR, default target/web) and
the myoslice wheel (the native reference run). scripts/test.sh provides all three.
"""

from __future__ import annotations

import base64
import functools
import http.server
import io
import json
import math
import os
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import websocket
from matplotlib import image as mpimg

ROOT = Path(__file__).resolve().parents[2]
WEB_DIR = Path(os.environ.get("MYOSLICE_WEB_DIR", ROOT / "target" / "web"))
HAMSTRINGS = ["semitendinosus", "semimembranosus", "biceps_femoris_long", "biceps_femoris_short"]
# Building the phantom single-threaded in wasm under a software renderer is slow.
LOAD_TIMEOUT_S = 600.0
RUN_TIMEOUT_S = 600.0


class Page:
    """One browser tab over the Chrome DevTools protocol."""

    def __init__(self, ws_url: str) -> None:
        # A call waits while the page's one thread builds a model.
        self.ws = websocket.create_connection(ws_url, timeout=LOAD_TIMEOUT_S)
        self.next_id = 0
        self.console: list[str] = []
        self.backend = ""

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        self.next_id += 1
        my_id = self.next_id
        self.ws.send(json.dumps({"id": my_id, "method": method, "params": params}))
        while True:
            msg = json.loads(self.ws.recv())
            if msg.get("method") == "Runtime.consoleAPICalled":
                args = msg["params"].get("args", [])
                self.console.append(" ".join(str(a.get("value", "")) for a in args))
            if msg.get("method") == "Runtime.exceptionThrown":
                self.console.append(json.dumps(msg["params"]["exceptionDetails"])[:2000])
            if msg.get("id") == my_id:
                if "error" in msg:
                    raise RuntimeError(f"{method}: {msg['error']}")
                result: dict[str, Any] = msg.get("result", {})
                return result

    def eval(self, expression: str) -> Any:
        r = self.call("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in r:
            raise RuntimeError(f"{expression}: {r['exceptionDetails']}")
        return r["result"].get("value")

    def status(self) -> dict[str, Any] | None:
        text = self.eval("window.myoslice && window.myoslice.status ? window.myoslice.status() : null")
        return json.loads(text) if text else None

    def wait_for(self, what: str, ok: Any, timeout: float) -> dict[str, Any]:
        end = time.monotonic() + timeout
        last = None
        while time.monotonic() < end:
            try:
                last = self.status()
            except RuntimeError:
                last = None
            if last is not None and ok(last):
                return last
            time.sleep(0.5)
        raise AssertionError(f"timed out waiting for {what}; last status {last}; console {self.console[-20:]}")

    def screenshot(self) -> np.ndarray:
        """The page as an RGB array; also saved to MYOSLICE_WEB_SCREENSHOT when set."""
        png = base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
        if path := os.environ.get("MYOSLICE_WEB_SCREENSHOT"):
            Path(path).write_bytes(png)
        img: np.ndarray = mpimg.imread(io.BytesIO(png), format="png")
        return (img[..., :3] * 255).round().astype(np.int32)


@pytest.fixture(scope="module")
def server() -> Iterator[str]:
    if not (WEB_DIR / "index.html").exists():
        pytest.fail(f"no web page in {WEB_DIR}: run scripts/web.sh first")
    handler = functools.partial(http.server.SimpleHTTPRequestHandler, directory=str(WEB_DIR))
    handler.extensions_map = {**http.server.SimpleHTTPRequestHandler.extensions_map, ".wasm": "application/wasm"}  # type: ignore[attr-defined]
    httpd = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()


# Chromium's flags for each graphics path: WebGL2 on SwiftShader through ANGLE (what a
# browser without WebGPU gives), and WebGPU on SwiftShader's Vulkan (behind flags in
# Chromium on Linux).
BACKENDS = {
    "WebGL2": ["--use-angle=swiftshader", "--enable-unsafe-swiftshader"],
    "WebGPU": [
        "--enable-unsafe-webgpu",
        "--enable-features=Vulkan,WebGPU",
        "--use-vulkan=swiftshader",
        "--use-webgpu-adapter=swiftshader",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
    ],
}


@pytest.fixture(scope="module", params=list(BACKENDS))
def page(server: str, request: pytest.FixtureRequest) -> Iterator[Page]:
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.fail("chromium is not installed (apt-get install chromium)")
    profile = tempfile.mkdtemp(prefix="myoslice-chromium-")
    proc = subprocess.Popen(
        [
            chromium,
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu-sandbox",
            "--no-first-run",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
            f"--user-data-dir={profile}",
            *BACKENDS[request.param],
            "--window-size=1280,800",
            "about:blank",
        ],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        port_file = Path(profile) / "DevToolsActivePort"
        end = time.monotonic() + 60
        while not port_file.exists() or not port_file.read_text().strip():
            if time.monotonic() > end or proc.poll() is not None:
                pytest.fail("chromium did not open its DevTools port")
            time.sleep(0.2)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list") as r:
            targets = json.load(r)
        ws_url = next(t["webSocketDebuggerUrl"] for t in targets if t.get("type") == "page")
        p = Page(ws_url)
        p.backend = request.param
        p.call("Runtime.enable")
        p.call("Page.enable")
        p.call("Page.navigate", url=f"{server}/index.html?paused")
        yield p
        p.ws.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:
            proc.kill()
        shutil.rmtree(profile, ignore_errors=True)


def native_knee_deg(seconds: float) -> float:
    """The same motion natively, on one thread: the phantom, hamstrings at 0.6."""
    os.environ.setdefault("RAYON_NUM_THREADS", "1")
    import myoslice

    sim = myoslice.Simulation.phantom()
    for name in HAMSTRINGS:
        sim.set_excitation(name, 0.6)
    sim.step(seconds)
    return math.degrees(sim.knee_angle)


def classify(img: np.ndarray, near: np.ndarray) -> tuple[int, int, int]:
    """Pixels of `img` (under the mask `near`) that differ from the background, and those
    coloured blue (grown) and red (shrunk) as the area map draws them."""
    # The view's clear colour: its top-right corner (the panel is on the left).
    background = img[2, -3]
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    leg = near & (np.abs(img - background).sum(axis=-1) > 30)
    blue = leg & (b > r + 40) & (b > g + 20)
    red = leg & (r > 120) & (r > g + 40) & (r > b + 40)
    return int(leg.sum()), int(blue.sum()), int(red.sum())


def test_the_page_flexes_the_knee_as_the_native_run_and_colours_the_skin_near_it(page: Page) -> None:
    ready = page.wait_for("the phantom and the graphics", lambda s: s["ready"] and s["frames"] > 2, LOAD_TIMEOUT_S)
    assert ready["error"] is None, ready
    assert ready["backend"] == page.backend, ready
    assert ready["time_s"] == 0.0, "the page was opened paused"
    page.eval("window.myoslice.preset('flexion')")
    t0 = time.monotonic()
    page.eval("window.myoslice.run_to(1.0)")
    done = page.wait_for(
        "1.0 s of flexion", lambda s: not s["running"] and s["time_s"] >= 1.0 - 1e-9, RUN_TIMEOUT_S
    )
    wall = time.monotonic() - t0
    assert done["error"] is None, done
    native = native_knee_deg(1.0)
    print(
        f"\nknee at 1.0 s: page {done['knee_deg']:.3f} deg ({done['backend']}), native {native:.3f} deg; "
        f"phantom built in {done['build_ms'] / 1e3:.1f} s in the page, first frame at "
        f"{ready['first_frame_ms'] / 1e3:.1f} s; 1.0 s simulated in {done['run_wall_s']:.2f} s of stepping "
        f"({wall:.1f} s with the frames between)"
    )
    assert native > 30.0, f"the native flexion barely moved: {native:.1f} deg"
    assert abs(done["knee_deg"] - native) < 0.5, (done, native)
    # A few frames to draw the flexed leg, then the picture.
    frames = done["frames"]
    page.wait_for("frames after the run", lambda s: s["frames"] > frames + 3, 120)
    img = page.screenshot()
    h, w = img.shape[:2]
    status = page.status()
    assert status is not None and status["knee_px"] is not None, status
    # The 3D view: right of the panel, above the page's bar.
    left = int(math.ceil(status["view_left_px"]))
    assert 100 < left < w // 2, status
    view = np.zeros((h, w), dtype=bool)
    view[: h - 40, left:] = True
    leg, _, _ = classify(img, view)
    share = leg / view.sum()
    print(f"the leg covers {share:.1%} of the view")
    assert 0.05 < share < 0.6, f"the leg covers {share:.1%} of the view"
    (kx, ky), per_m = status["knee_px"], status["px_per_m"]
    yy, xx = np.mgrid[0:h, 0:w]
    near = np.hypot(xx - kx, yy - ky) < 0.10 * per_m
    near_leg, blue, red = classify(img, near)
    assert near_leg > 200, f"the leg near the knee: {near_leg} pixels (knee at {kx:.0f}, {ky:.0f})"
    assert blue > 30 and red > 30, f"near the knee: blue {blue}, red {red} of {near_leg}"
    # The page's Save PNG: the canvas as drawn, not a cleared buffer.
    data_url = page.eval(
        "window.myoslicePage.snapshot().then((b) => new Promise((ok) => {"
        " const r = new FileReader(); r.onload = () => ok(r.result); r.readAsDataURL(b); }))"
    )
    assert data_url.startswith("data:image/png;base64,"), data_url[:40]
    saved = mpimg.imread(io.BytesIO(base64.b64decode(data_url.split(",", 1)[1])), format="png")
    saved = (saved[..., :3] * 255).round().astype(np.int32)
    width = page.eval("document.getElementById('myoslice-canvas').width")
    assert saved.shape[1] == width, (saved.shape, width)
    saved_view = np.zeros(saved.shape[:2], dtype=bool)
    saved_view[:, left:] = True
    drawn, _, _ = classify(saved, saved_view)
    assert drawn > saved_view.sum() * 0.05, f"the saved PNG shows {drawn} pixels of leg"


def test_frames_and_simulation_keep_going_when_playing(page: Page) -> None:
    start = page.wait_for("the page", lambda s: s["ready"], LOAD_TIMEOUT_S)
    page.eval("window.myoslice.set_playing(true)")
    t0 = time.monotonic()
    now = page.wait_for("8 s of play", lambda s: time.monotonic() - t0 > 8.0, 60)
    page.eval("window.myoslice.set_playing(false)")
    assert now is not None
    wall = time.monotonic() - t0
    frames = now["frames"] - start["frames"]
    simulated = now["time_s"] - start["time_s"]
    print(
        f"\nplaying for {wall:.1f} s: {frames} frames ({1e3 * wall / max(frames, 1):.0f} ms a frame), "
        f"{simulated:.2f} s simulated ({simulated / wall:.2f} s per s; the panel's speed is 0.5x)"
    )
    assert frames >= 2 and simulated > 0.0, now


def test_one_finger_turns_the_view_and_two_fingers_pinch_it(page: Page) -> None:
    page.wait_for("the page", lambda s: s["ready"] and s["knee_px"] is not None, LOAD_TIMEOUT_S)

    def touch(kind: str, points: list[tuple[float, float]]) -> None:
        page.call(
            "Input.dispatchTouchEvent",
            type=kind,
            touchPoints=[{"x": x, "y": y, "id": i} for i, (x, y) in enumerate(points)],
        )

    def settled() -> dict[str, Any]:
        frames = (page.status() or {}).get("frames", 0)
        return page.wait_for("a frame", lambda s: s["frames"] > frames + 1, 60)

    before = settled()
    # Right of the panel, over the view.
    x, y = 900.0, 300.0
    touch("touchStart", [(x, y)])
    for k in range(1, 6):
        touch("touchMove", [(x + 30.0 * k, y)])
    touch("touchEnd", [])
    turned = settled()
    moved = math.dist(turned["knee_px"], before["knee_px"])
    assert moved > 5.0, f"one finger did not turn the view: the knee moved {moved:.1f} px"
    assert abs(turned["px_per_m"] / before["px_per_m"] - 1.0) < 0.05, (before, turned)
    touch("touchStart", [(x - 50.0, y), (x + 50.0, y)])
    for k in range(1, 6):
        touch("touchMove", [(x - 50.0 - 20.0 * k, y), (x + 50.0 + 20.0 * k, y)])
    touch("touchEnd", [])
    pinched = settled()
    zoom = pinched["px_per_m"] / turned["px_per_m"]
    assert zoom > 1.3, f"spreading two fingers did not zoom in: x{zoom:.2f}"
    # A finger dragged on the panel is the panel's: the view stays.
    touch("touchStart", [(150.0, 150.0)])
    for k in range(1, 6):
        touch("touchMove", [(150.0 + 20.0 * k, 150.0 + 10.0 * k)])
    touch("touchEnd", [])
    after_panel = settled()
    assert math.dist(after_panel["knee_px"], pinched["knee_px"]) < 0.5, (pinched, after_panel)


def test_a_corrupt_nifti_gives_an_error_in_the_page_and_the_leg_keeps_running(page: Page) -> None:
    page.wait_for("the page", lambda s: s["ready"], LOAD_TIMEOUT_S)
    before = page.status()
    assert before is not None
    # A NIfTI header cut short after its magic-less first bytes.
    corrupt = list(b"\x5c\x01\x00\x00" + b"\x00" * 60)
    page.eval(f"window.myoslice.add_file('broken.nii', new Uint8Array({corrupt}))")
    page.eval("window.myoslice.open_files()")
    after = page.wait_for("the error", lambda s: s["error"] is not None, 120)
    assert "broken.nii" in after["error"], after
    assert after["model"] == before["model"], "the previous leg was replaced"
    # The message is on the page for the user, not only in the hook.
    end = time.monotonic() + 10
    shown = ""
    while "broken.nii" not in shown and time.monotonic() < end:
        shown = page.eval("document.getElementById('error').textContent") or ""
        time.sleep(0.2)
    assert "broken.nii" in shown, shown
    page.eval("window.myoslice.set_playing(true)")
    t0 = after["time_s"]
    page.wait_for("the leg running on", lambda s: s["time_s"] > t0 + 0.01, 120)


def test_your_own_leg_opens_from_a_volume_and_its_label_table(page: Page) -> None:
    data = ROOT.parent / "shared" / "data" / "visible-human"
    volume, labels = data / "vhf_left_leg_labels.nii.gz", data / "vhf_left_leg_labels.json"
    if not volume.exists():
        if os.environ.get("MYOSLICE_ALLOW_MISSING_DATA") == "1":
            pytest.skip(f"{volume} is missing (MYOSLICE_ALLOW_MISSING_DATA=1)")
        pytest.fail(f"{volume} is missing: ../shared/data must be beside the checkout")
    page.wait_for("the page", lambda s: s["ready"], LOAD_TIMEOUT_S)
    for f in (volume, labels):
        # Through the page's own file path (as a drop or the Open button hands them over).
        b64 = base64.b64encode(f.read_bytes()).decode()
        page.eval(
            f"window.myoslice.add_file('{f.name}', Uint8Array.from(atob('{b64}'), (c) => c.charCodeAt(0)))"
        )
    t0 = time.monotonic()
    page.eval("window.myoslice.open_files()")
    opened = page.wait_for(
        "the Visible Human leg", lambda s: s["model"] == volume.name or s["error"], LOAD_TIMEOUT_S
    )
    assert opened["error"] is None, opened
    print(f"\nthe Visible Human leg built in the page in {time.monotonic() - t0:.1f} s")
    page.eval("window.myoslice.preset('flexion')")
    target = opened["time_s"] + 0.3
    page.eval(f"window.myoslice.run_to({target})")
    moved = page.wait_for(
        "its flexion", lambda s: not s["running"] and s["time_s"] >= target - 1e-9, RUN_TIMEOUT_S
    )
    assert moved["error"] is None and moved["knee_deg"] > 5.0, moved
