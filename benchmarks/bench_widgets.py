"""Frame times of the notebook view (`marchlab.widgets.View`), kernel side, side by side.

    python benchmarks/bench_widgets.py [--scenes classroom,primitives,csg] [--size 480x360]
        [--frames 30]

Per scene: the median time of `get_frame` (render on the fastest backend, display encoding,
light marks) while the camera moves (the reduced picture) and at rest (full size), and the
time jupyter-rfb then takes to encode that picture for the browser (JPEG while moving, PNG at
rest), with the frames per second those allow the kernel. The browser's own decoding and the
network are not included. Markdown, for docs/performance.md.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time

import numpy as np


def median_ms(function, frames: int) -> tuple[float, object]:
    times, result = [], None
    for _ in range(frames):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return statistics.median(times) * 1e3, result


def main() -> None:
    from jupyter_rfb._jpg import array2jpg
    from jupyter_rfb._png import array2png
    from marchlab.widgets import View
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", default="classroom,primitives,csg")
    parser.add_argument("--size", default="480x360")
    parser.add_argument("--frames", type=int, default=30)
    args = parser.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    print("| scene | backend | moving: picture, get_frame, JPEG | at rest: picture, get_frame, "
          "PNG | fps moving / at rest |")
    print("|---|---|---|---|---|")
    for name in args.scenes.split(","):
        view = View(name, size=size)
        viewer = view.viewer

        def moving():
            viewer.drag("left", 2.0, 0.0)             # the camera moves every frame
            return view.canvas.get_frame()

        def at_rest():
            viewer._last_motion = -math.inf           # settled
            return view.canvas.get_frame()

        moving()                                      # compile and warm
        move_ms, small = median_ms(moving, args.frames)
        jpeg_ms, _ = median_ms(lambda: array2jpg(np.ascontiguousarray(small), quality=80),
                               args.frames)
        rest_ms, full = median_ms(at_rest, args.frames)
        png_ms, _ = median_ms(lambda: array2png(np.ascontiguousarray(full)), args.frames)
        print(f"| {name} | {view.canvas.backend} | {small.shape[1]}x{small.shape[0]}, "
              f"{move_ms:.1f} ms, {jpeg_ms:.1f} ms | {full.shape[1]}x{full.shape[0]}, "
              f"{rest_ms:.1f} ms, {png_ms:.1f} ms | "
              f"{1e3 / (move_ms + jpeg_ms):.0f} / {1e3 / (rest_ms + png_ms):.0f} |")


if __name__ == "__main__":
    main()
