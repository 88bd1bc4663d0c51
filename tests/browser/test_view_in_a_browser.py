"""The notebook view in a real browser: Voila, or JupyterLab as `make lessons` starts it,
serves a notebook with a `marchlab.widgets.View` on 127.0.0.1, Debian's Chromium (driven by
Playwright, no browser download) opens it, drags on the picture and moves a slider, and the
picture it then shows is the gpu backend's frame for the camera and setting the kernel moved
to, at the size the browser gave the view.

Needs chromium (a system package: `make test` installs it), Playwright and Voila (the dev
extra). Skipped where one is missing, or failed where ``make test`` sets
``MARCHLAB_REQUIRE_BROWSER=1``.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from required_backends import need_backend

REQUIRE = "MARCHLAB_REQUIRE_BROWSER"
CHROMIUM = ("chromium", "chromium-browser", "google-chrome")
SIZE = (240, 180)

NOTEBOOK = '''import json
from marchlab.widgets import View
view = View("classroom", controls=["render.max_steps"], size=({width}, {height}),
            markers=False)

def note(canvas):
    camera = view.viewer.camera
    with open("camera.json", "w") as file:
        json.dump({{"position": list(camera.position), "look_at": list(camera.look_at),
                   "max_steps": view.viewer.scene.render.max_steps,
                   "drawn": [canvas.frame.width, canvas.frame.height],
                   "view": list(view.viewer.size)}}, file)

view.canvas.on_draw.append(note)
view'''


def _missing() -> str | None:
    import importlib.util
    for module, what in (("playwright", "Playwright"), ("voila", "Voila"),
                         ("jupyter_rfb", "jupyter-rfb")):
        if importlib.util.find_spec(module) is None:
            return f"{what} is not installed (the dev and lessons extras)"
    if not any(shutil.which(name) for name in CHROMIUM):
        return "no chromium here (apt-get install chromium; make test installs it)"
    return None


@pytest.fixture
def browser_needs():
    need_backend("gpu")
    problem = _missing()
    if problem is None:
        return next(shutil.which(name) for name in CHROMIUM if shutil.which(name))
    if os.environ.get(REQUIRE):
        pytest.fail(f"{problem} (required by {REQUIRE}=1)", pytrace=False)
    pytest.skip(problem)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


SERVERS = {
    # Voila runs the notebook itself and shows its outputs.
    "voila": lambda port: [sys.executable, "-m", "voila", "--no-browser", f"--port={port}",
                           "--Voila.ip=127.0.0.1", "view.ipynb"],
    # JupyterLab as `make lessons` starts it (no token here: the test's browser is the user).
    "jupyterlab": lambda port: [sys.executable, "-m", "jupyterlab", "--no-browser",
                                f"--port={port}", "--ip=127.0.0.1", "--allow-root",
                                "--ServerApp.token=", "--ServerApp.password=",
                                "--ServerApp.root_dir=.", "--LabApp.news_url=",
                                "--LabApp.check_for_updates_class="
                                "jupyterlab.NeverCheckForUpdate"],
}
PAGES = {"voila": "", "jupyterlab": "lab/tree/view.ipynb"}


@pytest.fixture(params=list(SERVERS))
def served(request, tmp_path, browser_needs):
    """A server (Voila or JupyterLab) with a notebook holding a View, on 127.0.0.1 and a
    free port; stopped after."""
    import nbformat
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(NOTEBOOK.format(width=SIZE[0],
                                                                height=SIZE[1]))]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    nbformat.write(notebook, tmp_path / "view.ipynb")
    port = _free_port()
    log = open(tmp_path / "voila.log", "w")
    server = subprocess.Popen(SERVERS[request.param](port), cwd=tmp_path, stdout=log,
                              stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                time.sleep(0.2)
        yield (request.param, f"http://127.0.0.1:{port}/{PAGES[request.param]}", tmp_path,
               browser_needs)
    finally:
        server.terminate()
        try:
            server.wait(15)
        except subprocess.TimeoutExpired:
            server.kill()
        log.close()


def _run_the_cell(page) -> None:
    """JupyterLab shows the notebook; run its one cell, as a person would (Ctrl+Enter: run in
    place, so the notebook does not add a cell and scroll away from the view), and again if
    the kernel was not ready to take it (it starts as the page opens)."""
    page.wait_for_selector(".jp-Notebook .jp-Cell", timeout=90_000)
    for _ in range(6):
        page.locator(".jp-Notebook .jp-Cell .jp-InputArea-editor").first.click()
        page.keyboard.press("Control+Enter")
        try:
            page.wait_for_selector(".renderview-wrapper img", timeout=30_000)
            return
        except Exception:                    # Playwright's TimeoutError: try again
            continue
    raise AssertionError("JupyterLab ran the cell six times and showed no view")


def _camera_file(folder: Path, until, timeout: float = 30.0, settle: float = 1.0) -> dict:
    """The kernel's last drawn camera, once ``until(state)`` holds and the kernel has drawn
    nothing different for ``settle`` seconds: the browser sends a drag's moves as they come,
    so a frame drawn mid-drag (9 of 10 moves) would satisfy ``until`` too early."""
    deadline = time.monotonic() + timeout
    seen, since = None, time.monotonic()
    while time.monotonic() < deadline:
        try:
            state = json.loads((folder / "camera.json").read_text())
        except (OSError, ValueError):
            state = None
        if state != seen:
            seen, since = state, time.monotonic()
        elif state is not None and until(state) and time.monotonic() - since >= settle:
            return state
        time.sleep(0.1)
    raise AssertionError(f"the kernel drew no frame that satisfies the test in {timeout} s")


def _azimuth(state) -> float:
    offset = np.subtract(state["position"], state["look_at"])
    return math.degrees(math.atan2(offset[0], offset[2]))


def _screenshot(element) -> np.ndarray:
    import io
    from PIL import Image
    return np.asarray(Image.open(io.BytesIO(element.screenshot())).convert("RGB")).astype(int)


def test_a_drag_and_a_slider_in_the_browser_show_the_gpu_frame_of_the_edited_view(served):
    from playwright.sync_api import sync_playwright
    from marchlab.camera_control import ORBIT_DEGREES
    from scene_model.scenefile import load_scene
    server, url, folder, chromium = served
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium,
                                             args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.goto(url, timeout=90_000)
            if server == "jupyterlab":
                _run_the_cell(page)
            image = page.wait_for_selector(".renderview-wrapper img", timeout=90_000)
            first = _camera_file(folder, lambda state: state["drawn"] == state["view"])
            time.sleep(1.0)                               # the lossless frame at rest
            before = _screenshot(image)
            # Nothing over the picture: JupyterLab's notices ("news?") pop up bottom right.
            page.evaluate("document.querySelectorAll('.jp-toastContainer')"
                          ".forEach(toast => toast.remove())")
            image.scroll_into_view_if_needed()
            box = image.bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            for k in range(1, 11):                       # 30 px to the right, in 10 moves
                page.mouse.move(x + 3 * k, y)
                time.sleep(0.03)
            page.mouse.up()
            moved = _camera_file(folder, lambda state: abs(
                _azimuth(state) - _azimuth(first)) > 1 and state["drawn"] == state["view"])
            width, height = moved["view"]
            time.sleep(3.0)                               # the full-resolution PNG arrives
            after = _screenshot(image)
            # The max_steps slider, set by typing into its readout as a person can.
            page.locator(".widget-readout").first.click()
            page.keyboard.press("Control+A")
            page.keyboard.type("24")
            page.keyboard.press("Enter")
            stepped = _camera_file(folder, lambda state: state["max_steps"] == 24
                                   and state["drawn"] == [width, height])
            time.sleep(1.5)
            fewer_steps = _screenshot(image)
        finally:
            browser.close()
    # The kernel's camera turned by the window's orbit mapping (ImGui's drag threshold does
    # not apply here: every pixel of the drag counts).
    turned = _azimuth(moved) - _azimuth(first)
    assert turned == pytest.approx(-ORBIT_DEGREES * 30 / height, abs=0.5)
    # The browser shows the new picture: the gpu backend's frame for that camera, at the
    # size the browser gave the view (inside the element's 1 px border).
    assert np.abs(after - before).mean() > 5
    scene = load_scene("classroom")
    camera = dataclasses.replace(scene.camera, position=tuple(moved["position"]),
                                 look_at=tuple(moved["look_at"]))
    _assert_shows(after, dataclasses.replace(scene, camera=camera), width, height)
    # ... and after the slider, the frame of the same camera with max_steps 24.
    assert stepped["position"] == moved["position"]
    fewer = load_scene("classroom", ["render.max_steps=24"])
    _assert_shows(fewer_steps, dataclasses.replace(fewer, camera=camera), width, height)
    assert np.abs(fewer_steps - after).mean() > 1             # the picture changed


def _assert_shows(screenshot, scene, width, height):
    """The screenshot of the view's element holds the gpu backend's frame of ``scene`` at
    the size the browser gave the view, inside the element's border (1 px, and the element may
    sit on a fractional pixel, so the picture is looked for at each offset the slack allows)."""
    from marchlab.render import render
    expected = render(scene, width, height, backend="gpu").image().astype(int)
    best = 0.0
    for top in range(screenshot.shape[0] - height + 1):
        for left in range(screenshot.shape[1] - width + 1):
            inner = screenshot[top:top + height, left:left + width]
            best = max(best, (np.abs(inner - expected).max(axis=-1) <= 2).mean())
    assert best > 0.995, f"{best:.4f} of the pixels match"
