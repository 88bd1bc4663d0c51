"""Frames to an animation file: an animated GIF with Pillow, or an MP4 if imageio can write one.

Both writers leave a file whole or not at all (`scene_model.files.write_atomically`).
"""

from __future__ import annotations

import importlib.util
import io
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from scene_model.errors import MarchlabError
from scene_model.files import write_atomically

FORMATS = (".gif", ".mp4")


def gif_durations(frames: int, frame_seconds: float) -> list[int]:
    """Display time of each frame in ms, so that frame k starts at k frame_seconds.

    A GIF counts time in hundredths of a second; rounding each frame alone would play 30 fps
    (33.3 ms) as 30 ms frames, 10% fast. Rounding the start times instead lets the error of one
    frame be taken back by the next (33.3 ms becomes 30, 30, 40, 30, 30, 40, ...).
    """
    starts = [round(100 * k * frame_seconds) for k in range(frames + 1)]
    return [10 * (b - a) for a, b in zip(starts, starts[1:])]


def gif_bytes(images: list[np.ndarray], frame_seconds: float) -> bytes:
    """An animated GIF, looping forever, of ``images`` ((H, W, 3) uint8 each).

    Pillow merges a frame identical to the one before into it (adding their durations), so a
    GIF of a scene that has come to rest may hold fewer frames than ``images``.
    """
    pictures = [Image.fromarray(image) for image in images]
    buffer = io.BytesIO()
    pictures[0].save(buffer, format="GIF", save_all=True, append_images=pictures[1:],
                     duration=gif_durations(len(pictures), frame_seconds), loop=0)
    return buffer.getvalue()


def mp4_problem() -> str | None:
    """None if an .mp4 can be written here, else one line saying what to do instead."""
    missing = [name for name, module in (("imageio", "imageio"),
                                         ("imageio-ffmpeg", "imageio_ffmpeg"))
               if importlib.util.find_spec(module) is None]
    if missing:
        return (f"writing .mp4 needs {' and '.join(missing)} (pip install imageio "
                "imageio-ffmpeg); write a .gif instead")
    return None


def mp4_bytes(images: list[np.ndarray], fps: float) -> bytes:
    """An H.264 MP4 of ``images`` ((H, W, 3) uint8 each) at ``fps`` frames per second.

    The encoder (ffmpeg, through imageio) writes only to files, so it writes into a
    temporary folder that is removed afterwards, whatever happens.
    """
    problem = mp4_problem()
    if problem:
        raise MarchlabError(problem)
    import imageio.v2 as imageio
    with tempfile.TemporaryDirectory(prefix="marchlab-mp4-") as folder:
        path = Path(folder) / "animation.mp4"
        # H.264 in yuv420p needs even sides; imageio stretches an odd side by one pixel.
        imageio.mimwrite(path, images, format="FFMPEG", fps=fps, macro_block_size=2)
        return path.read_bytes()


def write_mp4(path, images: list[np.ndarray], fps: float) -> None:
    """Write ``images`` as an H.264 MP4 at ``fps`` frames per second, atomically."""
    problem = mp4_problem()
    if problem:
        raise MarchlabError(f"{path}: {problem}")
    write_atomically(path, mp4_bytes(images, fps))
