"""The notebook view in a real browser: Voila serves a notebook with a `marchlab.widgets.View`
on 127.0.0.1, Debian's Chromium (driven by Playwright, no browser download) opens it, drags on
the picture, and the picture it then shows is the gpu backend's frame for the camera the
kernel moved to, at the size the browser gave the view.

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


@pytest.fixture
def voila(tmp_path, browser_needs):
    """Voila serving a notebook with a View, on 127.0.0.1 and a free port; stopped after."""
    import nbformat
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(NOTEBOOK.format(width=SIZE[0],
                                                                height=SIZE[1]))]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    nbformat.write(notebook, tmp_path / "view.ipynb")
    port = _free_port()
    log = open(tmp_path / "voila.log", "w")
    server = subprocess.Popen([sys.executable, "-m", "voila", "--no-browser", f"--port={port}",
                               "--Voila.ip=127.0.0.1", "view.ipynb"], cwd=tmp_path,
                              stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                socket.create_connection(("127.0.0.1", port), timeout=0.2).close()
                break
            except OSError:
                time.sleep(0.2)
        yield f"http://127.0.0.1:{port}/", tmp_path, browser_needs
    finally:
        server.terminate()
        try:
            server.wait(15)
        except subprocess.TimeoutExpired:
            server.kill()
        log.close()


def _camera_file(folder: Path, until, timeout: float = 30.0) -> dict:
    """The kernel's last drawn camera, once ``until(state)`` holds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            state = json.loads((folder / "camera.json").read_text())
            if until(state):
                return state
        except (OSError, ValueError):
            pass
        time.sleep(0.2)
    raise AssertionError(f"the kernel drew no frame that satisfies the test in {timeout} s")


def _azimuth(state) -> float:
    offset = np.subtract(state["position"], state["look_at"])
    return math.degrees(math.atan2(offset[0], offset[2]))


def _screenshot(element) -> np.ndarray:
    import io
    from PIL import Image
    return np.asarray(Image.open(io.BytesIO(element.screenshot())).convert("RGB")).astype(int)


def test_a_drag_and_a_slider_in_the_browser_show_the_gpu_frame_of_the_edited_view(voila):
    from playwright.sync_api import sync_playwright
    from marchlab.camera_control import ORBIT_DEGREES
    from scene_model.scenefile import load_scene
    url, folder, chromium = voila
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium,
                                             args=["--no-sandbox"])
        try:
            page = browser.new_page(viewport={"width": 800, "height": 600})
            page.goto(url, timeout=90_000)
            image = page.wait_for_selector(".renderview-wrapper img", timeout=90_000)
            first = _camera_file(folder, lambda state: True)
            time.sleep(1.0)                               # the lossless frame at rest
            before = _screenshot(image)
            box = image.bounding_box()
            x, y = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            page.mouse.move(x, y)
            page.mouse.down()
            for k in range(1, 11):                       # 30 px to the right, in 10 moves
                page.mouse.move(x + 3 * k, y)
                time.sleep(0.03)
            page.mouse.up()
            width, height = first["view"]
            moved = _camera_file(folder, lambda state: abs(
                _azimuth(state) - _azimuth(first)) > 1 and state["drawn"] == [width, height])
            time.sleep(1.5)                               # the full-resolution PNG arrives
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
    the size the browser gave the view (inside the element's 1 px border)."""
    from marchlab.render import render
    expected = render(scene, width, height, backend="gpu").image().astype(int)
    top, left = (screenshot.shape[0] - height) // 2, (screenshot.shape[1] - width) // 2
    inner = screenshot[top:top + height, left:left + width]
    close = np.abs(inner - expected).max(axis=-1) <= 2
    assert close.mean() > 0.995, f"{close.mean():.4f} of the pixels match"
