"""Make docs/video.jpg: frames of a video taken from a pan-tilt unit, before and after
`gsrwt rectify VIDEO --poses LOG`.

A camera (640x480, f = 600 px) on a pan-tilt unit sweeps across the corridor wall of
`sample_data/corridor_wall.png` (pan from 30 to -6 degrees, tilt from 18 down to 4, in three
seconds at 15 frames per second). The frames are rendered by `gsrwt_cli.render_view` and
encoded losslessly (FFV1 in Matroska) by PyAV; the pose log has a row every fifth frame, so
that gsrwt interpolates (slerp) the poses between them. The figure's top row is three
frames of the input, the bottom row the same frames of gsrwt's output (each in its default
frontal frame, centred where the camera's axis meets the wall): the door stands square in
every one. Needs `pip install '.[video]'`.

    python docs/make_video_figure.py
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
from fractions import Fraction
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gsrwt_cli import View, render_view  # noqa: E402

WIDTH, HEIGHT, FOCAL, RATE, SECONDS = 640, 480, 600.0, 15, 3.0
SHOWN = (0, 22, 44)  # the frames in the figure
TILE_HEIGHT = 200
MARGIN = 8


def pose_at(time: float) -> tuple[float, float]:
    """(pan, tilt) in degrees at ``time`` seconds: the sweep."""
    return 30 - 36 * time / SECONDS, 18 - 14 * time / SECONDS


def write_video(path: Path, frames: list[np.ndarray]) -> None:
    """Encode BGR ``frames`` at :data:`RATE` with PyAV, FFV1 (lossless)."""
    import av

    with av.open(str(path), mode="w") as container:
        stream = container.add_stream("ffv1", rate=RATE)
        stream.width, stream.height, stream.pix_fmt = WIDTH, HEIGHT, "bgr0"
        stream.time_base = Fraction(1, 1000)
        for index, image in enumerate(frames):
            frame = av.VideoFrame.from_ndarray(image, format="bgr24")
            frame.pts, frame.time_base = round(index * 1000 / RATE), Fraction(1, 1000)
            container.mux(stream.encode(frame))
        container.mux(stream.encode())


def read_frames(path: Path, wanted: tuple[int, ...]) -> list[np.ndarray]:
    """The frames of index ``wanted`` of the video at ``path``, BGR."""
    import av

    with av.open(str(path)) as container:
        frames = [frame.to_ndarray(format="bgr24")
                  for frame in container.decode(video=0)]
    return [frames[index] for index in wanted]


def tile(image: np.ndarray) -> np.ndarray:
    factor = TILE_HEIGHT / image.shape[0]
    return cv2.resize(image, (round(image.shape[1] * factor), TILE_HEIGHT),
                      interpolation=cv2.INTER_AREA)


def row(images: list[np.ndarray]) -> np.ndarray:
    tiles = [tile(image) for image in images]
    gap = np.full((TILE_HEIGHT, MARGIN, 3), 255, np.uint8)
    parts = [part for image in tiles for part in (image, gap)][:-1]
    return np.hstack(parts)


def main() -> None:
    texture = cv2.imread(str(ROOT / "sample_data" / "corridor_wall.png"))
    count = round(SECONDS * RATE)
    times = [index / RATE for index in range(count)]
    frames = []
    for time in times:
        pan, tilt = pose_at(time)
        view = View(pan=pan, tilt=tilt, focal=FOCAL, width=WIDTH, height=HEIGHT)
        frames.append(render_view(texture, view))
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        video = work / "sweep.mkv"
        write_video(video, frames)
        log = ["time,pan,tilt"] + [f"{time:.4f},{pose_at(time)[0]:.4f},{pose_at(time)[1]:.4f}"
                                   for time in times[::5] + [times[-1]]]
        (work / "poses.csv").write_text("\n".join(log) + "\n")
        subprocess.run([sys.executable, "-m", "gsrwt_cli", "rectify", str(video), "--poses",
                        str(work / "poses.csv"), "--focal", str(FOCAL), "--codec", "ffv1",
                        "-o", str(work / "out"), "-q"], check=True)
        before = [frames[index] for index in SHOWN]
        after = read_frames(work / "out" / "sweep.mkv", SHOWN)
    top, bottom = row(before), row(after)
    width = max(top.shape[1], bottom.shape[1])

    def padded(image: np.ndarray) -> np.ndarray:
        return cv2.copyMakeBorder(image, 0, 0, 0, width - image.shape[1], cv2.BORDER_CONSTANT,
                                  value=(255, 255, 255))

    gap = np.full((MARGIN, width, 3), 255, np.uint8)
    cv2.imwrite(str(ROOT / "docs" / "video.jpg"), np.vstack([padded(top), gap, padded(bottom)]),
                [cv2.IMWRITE_JPEG_QUALITY, 85])


if __name__ == "__main__":
    main()
