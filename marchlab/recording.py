"""Recordings of a live view: the session as it is shown, or a turntable.

`Recorder` collects frames and writes them to an MP4 or a GIF with imageio (its ffmpeg
plugin for MP4). `Turntable` turns the camera once about its pivot, one frame per step at
full resolution, for a loop a teacher can put on a slide. The window (`marchlab.view_window`)
feeds both, one frame per window frame, so it stays live while it records.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from scene_model.errors import MarchlabError
from scene_model.files import write_atomically

from .camera_control import turntable

SUFFIXES = (".mp4", ".gif")


def recording_problem(path) -> str | None:
    """None if ``path`` names a recording this module writes, else why not."""
    if Path(path).suffix.lower() not in SUFFIXES:
        return f"{path}: a recording is an .mp4 or a .gif"
    return None


class Recorder:
    """Frames of the view, written to an MP4 or GIF (imageio) by `finish`.

    Every frame is stored at the first frame's size: one drawn at a reduced resolution
    while the camera moved is scaled up to it (nearest pixel), as the window shows it.
    """

    def __init__(self, path, fps: float = 30.0):
        if (problem := recording_problem(path)) is not None:
            raise MarchlabError(problem)
        self.path = Path(path)
        self.frames: list[np.ndarray] = []
        self.fps = fps

    def add(self, image: np.ndarray) -> None:
        """Add an (H, W, 3) uint8 frame."""
        if self.frames and image.shape != self.frames[0].shape:
            image = scale_nearest(image, self.frames[0].shape[:2])
        self.frames.append(image)

    def finish(self) -> Path:
        """Write the recording (atomically: no half-written file) and return its path."""
        if not self.frames:
            raise MarchlabError("nothing was recorded")
        import imageio.v3 as iio
        buffer = io.BytesIO()
        extension = self.path.suffix.lower()
        options = ({"fps": self.fps} if extension == ".mp4"
                   else {"duration": 1000 / self.fps, "loop": 0})
        iio.imwrite(buffer, np.stack(self.frames), extension=extension, **options)
        write_atomically(self.path, buffer.getvalue())
        return self.path


def scale_nearest(image: np.ndarray, shape) -> np.ndarray:
    """``image`` (h, w, C) resampled to ``shape`` (H, W) by the nearest pixel: output pixel
    (i, j) takes input pixel (i h // H, j w // W)."""
    rows = np.arange(shape[0]) * image.shape[0] // shape[0]
    cols = np.arange(shape[1]) * image.shape[1] // shape[1]
    return image[rows][:, cols]


class Turntable:
    """One turn of the camera about its pivot, recorded a frame at a time.

    Parameters
    ----------
    path : str or os.PathLike
        The .mp4 or .gif to write.
    camera : scene_model.scene.Camera
        Where the turn starts (`marchlab.camera_control.turntable`).
    frames : int
        Frames in the turn (at ``fps``, the loop lasts frames / fps seconds).
    """

    def __init__(self, path, camera, frames: int = 72, fps: float = 30.0):
        if frames < 2:
            raise MarchlabError(f"a turntable needs at least 2 frames (got {frames})")
        self.recorder = Recorder(path, fps)
        self.start = camera
        self.cameras = turntable(camera, frames)

    @property
    def finished(self) -> bool:
        return len(self.recorder.frames) == len(self.cameras)

    def next_camera(self):
        """The camera of the next frame to record."""
        return self.cameras[len(self.recorder.frames)]

    def add(self, image: np.ndarray) -> None:
        """The picture seen from `next_camera`."""
        self.recorder.add(image)

    def finish(self) -> Path:
        return self.recorder.finish()
