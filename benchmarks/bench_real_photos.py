"""Accuracy, refusals, confidence and time of ``gsrwt estimate`` on real photos with a known
orientation: the York Urban DB's training half (51 photos, 640x480, one calibrated camera).

Three runs of ``gsrwt estimate`` over all the photos, each one subprocess:

- **calibrated focal**: a sidecar gives each photo its calibrated focal length and principal
  point (``truth.csv``);
- **no focal**: copies of the photos with their EXIF removed (losslessly: the JPEG's APP1
  segments dropped, the image data untouched) and no intrinsics at all, so the focal length is
  estimated from the image and the principal point is the image's centre;
- **EXIF focal**: the photos as taken, as a photographer would give them: the focal length
  from their EXIF (about 4 % off the calibrated one), the principal point the image's centre.

Measured as the data's README says (``benchmarks/real_photos.py``): the angle between the
estimated and true world-up, and between the estimated wall normal and the nearer true
horizontal (as lines), median / 90th percentile / worst, an image with no estimate counting
90 degrees; the refusals (status not ok); the "confidently wrong" (status ok and more than
3 degrees off on either measure); the focal length's error where estimated; the calibration
of ``confidence`` (per bin, the fraction within 2 degrees on both measures); CPU time of the
subprocess (it and its workers) and wall time, per photo, the program's start included; and
the estimate alone in this process (:func:`estimate_cpu_ms`).

Then the photos of other kinds (``tests/data/real``): ``gsrwt estimate`` and ``rectify --auto``
with no focal length, and ``gsrwt estimate`` given each photo a focal length of
:data:`FOCAL_FACTORS` times its long side: which of those that must be refused get ``ok``.
Last, OpenCV's chessboard photos of its two webcams (``tests/data/right*.jpg``,
``left*.jpg``), their calibration given and then not: each board's plane taken as the wall
and measured against its pose (:func:`evaluate_chessboards`).

    python benchmarks/bench_real_photos.py [PATH-TO-york-urban-train] [--json] [--jobs N]
        [--two-directions] [--smaller] [--telephoto] [--altered]
    python benchmarks/bench_real_photos.py --survey FOLDER [--long-side 640]

``--two-directions`` adds the York photos seen with one horizontal direction's edges left out
(:func:`evaluate_two_directions`): views of a wall about frontally, and of a corridor.
``--smaller`` adds them shrunk (:func:`evaluate_smaller`), ``--telephoto`` cropped around the
principal point as a longer lens would have seen them (:func:`evaluate_telephoto`),
``--altered`` re-encoded, noisier, blurred, brightened and darkened (:func:`evaluate_altered`).
``--survey FOLDER`` only estimates every photo of a folder nobody measured
(:func:`survey_photos`), to look for photos that get a pose they should not.

PATH defaults to ``../shared/data/york-urban-train`` beside the repository.
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import real_photos as measure  # noqa: E402

if TYPE_CHECKING:
    from gsrwt_cli.geometry.camera import Intrinsics

REPOSITORY = Path(__file__).resolve().parent.parent
DEFAULT_DATA = REPOSITORY.parent / "shared" / "data" / "york-urban-train"
OTHER_PHOTOS = REPOSITORY / "tests" / "data" / "real"
#: OpenCV's chessboard photos, their camera and their poses (``cv2.solvePnP`` of the corners):
#: ``tests/data/README.md``.
BOARDS = REPOSITORY / "tests" / "data"
GSRWT = Path(sys.executable).with_name("gsrwt")


@dataclass
class PhotoResult:
    """One photo's estimate and its errors."""

    image: str
    status: str
    confidence: float | None
    focal: float | None
    focal_source: str
    true_focal: float
    vertical: float
    wall: float
    error: str


@dataclass
class RunResult:
    """One ``gsrwt estimate`` run over all the photos."""

    name: str
    photos: list[PhotoResult]
    cpu_seconds: float
    wall_seconds: float
    vertical: measure.Summary = field(init=False)
    wall: measure.Summary = field(init=False)

    def __post_init__(self) -> None:
        self.vertical = measure.summarize(p.vertical for p in self.photos)
        self.wall = measure.summarize(p.wall for p in self.photos)

    @property
    def refused(self) -> list[PhotoResult]:
        return [p for p in self.photos if p.status != "ok"]

    @property
    def confidently_wrong(self) -> list[PhotoResult]:
        return [p for p in self.photos if measure.is_confidently_wrong(
            p.status == "ok", measure.ImageErrors(p.vertical, p.wall))]

    def focal_errors(self) -> measure.Summary:
        """Relative error of the focal length (percent) over the ok photos whose focal length
        was estimated, or refined from their EXIF's (``exif+lines``)."""
        return measure.summarize(
            100 * measure.relative_error(p.focal, p.true_focal) for p in self.photos
            if p.status == "ok" and p.focal_source in ("estimated", "exif+lines")
            and p.focal is not None)

    def calibration(self) -> list[measure.CalibrationBin]:
        ok = [p for p in self.photos if p.status == "ok" and p.confidence is not None]
        return measure.calibration_bins(
            [p.confidence for p in ok],
            [measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok])


def read_truth(data: Path) -> dict[str, dict[str, str]]:
    """``truth.csv``'s rows by image name."""
    with open(data / "truth.csv", newline="") as file:
        return {row["image"]: row for row in csv.DictReader(file)}


def true_directions(row: dict[str, str]) -> measure.SceneDirections:
    """The truth row's ``up_*``, ``wall_*``, ``side_*`` vectors (OpenCV camera frame)."""
    return measure.SceneDirections(*(
        np.array([float(row[f"{name}_{axis}"]) for axis in "xyz"])
        for name in ("up", "wall", "side")))


def strip_exif(jpeg: bytes) -> bytes:
    """The JPEG without its APP1 segments (EXIF, XMP): the segments before the scan are
    walked by their lengths and every other byte is kept, so the pixels do not change."""
    if jpeg[:2] != b"\xff\xd8":
        raise ValueError("not a JPEG (no SOI marker)")
    kept, position = [jpeg[:2]], 2
    while position + 4 <= len(jpeg) and jpeg[position] == 0xFF:
        marker = jpeg[position + 1]
        if marker == 0xDA:  # start of scan: the rest is image data
            break
        end = position + 2 + int.from_bytes(jpeg[position + 2:position + 4], "big")
        if marker != 0xE1:
            kept.append(jpeg[position:end])
        position = end
    kept.append(jpeg[position:])
    return b"".join(kept)


def run_estimate(images: Path | list[Path], sidecar: Path | None, jobs: int, output: Path,
                 camera: Path | None = None) -> tuple[list[dict[str, str]], float, float]:
    """``gsrwt estimate IMAGES [--sidecar S] [--camera C] -o OUTPUT``: its rows, the CPU seconds
    of the subprocess and its workers, and the wall seconds."""
    paths = images if isinstance(images, list) else [images]
    command = [str(GSRWT), "estimate", *map(str, paths), "-o", str(output), "-j", str(jobs),
               "-q"]
    if sidecar is not None:
        command += ["--sidecar", str(sidecar)]
    if camera is not None:
        command += ["--camera", str(camera)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode not in (0, 1) or not output.exists():
        raise SystemExit(f"gsrwt estimate failed (exit {done.returncode}): {done.stderr.strip()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    with open(output, newline="") as file:
        return list(csv.DictReader(file)), cpu, wall


def _number(text: str) -> float | None:
    return float(text) if text not in ("", None) else None


def measure_run(name: str, rows: list[dict[str, str]], truth: dict[str, dict[str, str]],
                cpu: float, wall: float) -> RunResult:
    """Each photo's errors from ``gsrwt estimate``'s rows (a photo without a row counts as
    refused)."""
    by_image = {row["image"]: row for row in rows}
    photos = []
    for image, true in sorted(truth.items()):
        row = by_image.get(image, {"status": "missing", "error": "no row in the output"})
        ok = row.get("status") == "ok"
        estimate = (measure.directions_from_pose(float(row["pan"]), float(row["tilt"]),
                                                 float(row["roll"])) if ok else None)
        errors = measure.image_errors(estimate, true_directions(true))
        focal = _number(row.get("focal", "")) or (
            math.sqrt(float(row["fx"]) * float(row["fy"])) if row.get("fx") else None)
        photos.append(PhotoResult(
            image, row.get("status", ""), _number(row.get("confidence", "")), focal,
            row.get("focal_source", ""), float(true["focal_px"]), errors.vertical, errors.wall,
            row.get("error", "")))
    return RunResult(name, photos, cpu, wall)


def evaluate(data: Path, jobs: int = 1) -> list[RunResult]:
    """The three runs (calibrated focal; no focal, EXIF removed; the photos as taken, their
    EXIF focal length about 4 % off and the principal point the image's centre) over the
    photos in ``data``."""
    truth = read_truth(data)
    with tempfile.TemporaryDirectory(prefix="gsrwt-york-") as temporary:
        scratch = Path(temporary)
        sidecar = scratch / "calibrated.csv"
        with open(sidecar, "w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow(["image", "focal", "cx", "cy"])
            for image, row in truth.items():
                writer.writerow([image, row["focal_px"], row["cx"], row["cy"]])
        bare = scratch / "no-exif"
        bare.mkdir()
        for image in truth:
            (bare / image).write_bytes(strip_exif((data / "images" / image).read_bytes()))
        runs = []
        for name, images, given in (("calibrated focal", data / "images", sidecar),
                                    ("no focal (EXIF removed)", bare, None),
                                    ("EXIF focal (as taken)", data / "images", None)):
            rows, cpu, wall = run_estimate(images, given, jobs, scratch / f"{len(runs)}.csv")
            runs.append(measure_run(name, rows, truth, cpu, wall))
    return runs


#: Passes over the photos when timing the estimate alone (the quickest counts).
IN_PROCESS_PASSES = 3


def estimate_cpu_ms(data: Path, passes: int = IN_PROCESS_PASSES) -> float:
    """CPU milliseconds per photo of the estimate alone (``estimate_pose`` with the calibrated
    focal length and principal point) in this process, OpenCV on one thread, the photos
    decoded beforehand: the quickest of ``passes`` passes over them. What issue 23's "no
    slower than about 25 ms of CPU per 640x480 photo" counts: the command's own times above
    also start Python and read the photos."""
    from gsrwt_cli.api.estimate import estimate_pose
    from gsrwt_cli.geometry.camera import Intrinsics

    cv2.setNumThreads(1)
    photos = []
    for image, row in read_truth(data).items():
        pixels = cv2.imread(str(data / "images" / image))
        height, width = pixels.shape[:2]
        focal = float(row["focal_px"])
        photos.append((pixels, Intrinsics(focal, focal, float(row["cx"]), float(row["cy"]),
                                          width=width, height=height)))
    quickest = math.inf
    for _ in range(passes):
        start = time.process_time()
        for pixels, camera in photos:
            estimate_pose(pixels, camera)
        quickest = min(quickest, time.process_time() - start)
    return 1000 * quickest / len(photos)


#: :func:`evaluate_two_directions`: a detected segment within this many pixels (end-point
#: distance) of a true direction's vanishing line is taken for one of its edges, and left out.
LEFT_OUT_PX = 3.0
#: The factors :func:`evaluate_smaller` shrinks the York photos by (480x360 and 320x240).
SMALLER_FACTORS = (0.75, 0.5)
#: The share of each side :func:`evaluate_telephoto` keeps of a York photo, around its
#: principal point: 1.5, 2.1, 2.6 and 3.2 times the long side as the focal length.
TELEPHOTO_FRACTIONS = (0.7, 0.5, 0.4, 1 / 3)


def _recompressed(pixels: np.ndarray, quality: int) -> np.ndarray:
    """``pixels`` through a JPEG of ``quality`` (OpenCV's encoder), decoded again."""
    encoded = cv2.imencode(".jpg", pixels, [cv2.IMWRITE_JPEG_QUALITY, quality])[1]
    return cv2.imdecode(encoded, cv2.IMREAD_COLOR)


def _with_noise(pixels: np.ndarray, sigma: float, seed: int) -> np.ndarray:
    """``pixels`` plus Gaussian noise of ``sigma`` grey levels (seeded), rounded and clipped."""
    noise = np.random.default_rng(seed).normal(0.0, sigma, pixels.shape)
    return np.clip(np.rint(pixels + noise), 0, 255).astype(np.uint8)


#: What a photo may go through before it reaches gsrwt, none of which moves its geometry
#: (:func:`evaluate_altered`): each takes the pixels and the photo's index (a seed).
ALTERATIONS = {
    "JPEG quality 60": lambda pixels, index: _recompressed(pixels, 60),
    "noise 4 grey levels": lambda pixels, index: _with_noise(pixels, 4.0, index),
    "blurred 1 px": lambda pixels, index: cv2.GaussianBlur(pixels, (0, 0), 1.0),
    "shadows brightened (gamma 0.6)": lambda pixels, index: np.rint(
        255.0 * (pixels / 255.0) ** 0.6).astype(np.uint8),
    "underexposed (x0.35)": lambda pixels, index: np.rint(pixels * 0.35).astype(np.uint8),
}


def estimates_without(data: Path, dropped: str) -> Iterator[tuple[str, object,
                                                                 measure.SceneDirections]]:
    """Each York photo (in sorted order) seen with one true direction's edges gone, in this
    process: the segments ``gsrwt estimate`` detects, less those along the true ``dropped``
    (``wall``: the wall normal, leaving a wall seen about frontally; ``side``: the other
    horizontal, leaving a corridor's verticals and receding edges, :func:`measure.
    along_direction`), estimated with the calibrated focal length and principal point: the
    photo's name, the estimate and the true directions."""
    from gsrwt_cli.api.estimate import detect_segments, estimate_pose
    from gsrwt_cli.geometry.camera import Intrinsics

    cv2.setNumThreads(1)
    for image, row in sorted(read_truth(data).items()):
        pixels = cv2.imread(str(data / "images" / image))
        height, width = pixels.shape[:2]
        focal, cx, cy = (float(row[key]) for key in ("focal_px", "cx", "cy"))
        lines = detect_segments(pixels)
        truth = true_directions(row)
        matrix = np.array([[focal, 0, cx], [0, focal, cy], [0, 0, 1.0]])
        kept = lines[~measure.along_direction(lines, matrix, getattr(truth, dropped),
                                              LEFT_OUT_PX)]
        yield image, estimate_pose(pixels, Intrinsics(focal, focal, cx, cy, width=width,
                                                      height=height), lines=kept), truth


def evaluate_two_directions(data: Path) -> list[RunResult]:
    """The York photos as walls seen about frontally and as corridors
    (:func:`estimates_without`): views the photos do not show as a whole, made of their real
    edges, each estimate measured as the whole photos' are."""
    from gsrwt_cli.api.estimate import DEFAULT_MIN_CONFIDENCE

    runs = []
    for name, dropped in (("frontal wall (no receding edges)", "wall"),
                          ("vertical and receding edges only", "side")):
        photos = []
        for image, estimate, truth in estimates_without(data, dropped):
            ok = estimate.error is None and estimate.confidence >= DEFAULT_MIN_CONFIDENCE
            errors = measure.image_errors(
                measure.directions_from_pose(estimate.pose.pan, estimate.pose.tilt,
                                             estimate.pose.roll) if ok else None, truth)
            focal = estimate.focal
            photos.append(PhotoResult(image, "ok" if ok else "error", estimate.confidence,
                                      focal, "sidecar", focal, errors.vertical, errors.wall,
                                      estimate.error or ""))
        runs.append(RunResult(name, photos, 0.0, 0.0))
    return runs


def report_two_directions(runs: list[RunResult]) -> str:
    """The lines of :func:`evaluate_two_directions`, as text."""
    lines = ["York photos with one horizontal direction's edges left out (in process, "
             "calibrated focal):"]
    for run in runs:
        ok = [p for p in run.photos if p.status == "ok"]
        within = sum(measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok)
        wrong = ", ".join(f"{p.image} {p.vertical:.1f}/{p.wall:.1f}"
                          for p in run.confidently_wrong)
        lines.append(f"  {run.name:34s} ok {len(ok)} of {len(run.photos)}, within 2 deg "
                     f"{within}, confidently wrong {len(run.confidently_wrong)}"
                     f"{': ' + wrong if wrong else ''}")
    return "\n".join(lines)


def _estimated_view(image: str, row: dict[str, str], pixels: np.ndarray, camera: Intrinsics,
                    exif: bool = False) -> PhotoResult:
    """A York photo's ``pixels`` (shrunk, cropped...) estimated in this process with
    ``camera`` given, and measured against its truth ``row``. ``exif``: ``camera``'s focal
    length is EXIF's, and is treated as ``gsrwt estimate`` treats it: refined by the segments
    (:data:`~gsrwt_cli.api.estimate.EXIF_FOCAL_SPREAD`), the estimate checked for a lens."""
    from gsrwt_cli.api.estimate import DEFAULT_MIN_CONFIDENCE, estimate_pose
    from gsrwt_cli.batch.estimate_jobs import EstimateOptions, estimate_as_given

    if exif:
        estimate = estimate_as_given(pixels, camera, "exif", {}, None, EstimateOptions())
    else:
        estimate = estimate_pose(pixels, camera)
    ok = estimate.error is None and estimate.confidence >= DEFAULT_MIN_CONFIDENCE
    errors = measure.image_errors(
        measure.directions_from_pose(estimate.pose.pan, estimate.pose.tilt,
                                     estimate.pose.roll) if ok else None,
        true_directions(row))
    # the view's true focal length: the one given (scaled with a shrunk or cropped view), or
    # with EXIF's the calibrated one (the photo as taken)
    focal, source, true_focal = ((estimate.focal, "exif+lines", float(row["focal_px"])) if exif
                                 else (camera.focal, "sidecar", camera.focal))
    return PhotoResult(image, "ok" if ok else "error", estimate.confidence, focal, source,
                       true_focal, errors.vertical, errors.wall, estimate.error or "")


def evaluate_smaller(data: Path, factors: tuple[float, ...] = SMALLER_FACTORS
                     ) -> list[RunResult]:
    """The York photos shrunk by each of ``factors`` (area averaging; 0.5 makes 320x240),
    their focal length and principal point scaled with them, estimated in this process with
    the focal length given and measured as the photos as taken are."""
    from gsrwt_cli.geometry.camera import Intrinsics

    cv2.setNumThreads(1)
    runs = []
    for factor in factors:
        photos = []
        for image, row in sorted(read_truth(data).items()):
            pixels = cv2.imread(str(data / "images" / image))
            height, width = pixels.shape[:2]
            size = (round(width * factor), round(height * factor))
            pixels = cv2.resize(pixels, size, interpolation=cv2.INTER_AREA)
            focal, cx, cy = (float(row[key]) for key in ("focal_px", "cx", "cy"))
            camera = Intrinsics(focal * factor, focal * factor, (cx + 0.5) * factor - 0.5,
                                (cy + 0.5) * factor - 0.5, width=size[0], height=size[1])
            photos.append(_estimated_view(image, row, pixels, camera))
        runs.append(RunResult(f"{size[0]}x{size[1]}", photos, 0.0, 0.0))
    return runs


def telephoto_view(pixels: np.ndarray, camera: Intrinsics, fraction: float,
                   enlarge: bool = False) -> tuple[np.ndarray, Intrinsics]:
    """The part of ``pixels`` (seen through the pinhole ``camera``) ``fraction`` of each side
    wide and high around the principal point (moved inside the image where it must be): what
    a lens of ``1 / fraction`` times the focal length would have seen, with the camera that
    sees it (the principal point shifted; the orientation unchanged). ``enlarge``: resized
    back to the photo's size (bicubic), the focal length and principal point scaled with it,
    as a telephoto photo of as many pixels."""
    from gsrwt_cli.geometry.camera import Intrinsics

    height, width = pixels.shape[:2]
    size = (round(width * fraction), round(height * fraction))
    left = min(max(round(camera.cx - size[0] / 2), 0), width - size[0])
    top = min(max(round(camera.cy - size[1] / 2), 0), height - size[1])
    view = np.ascontiguousarray(pixels[top:top + size[1], left:left + size[0]])
    cx, cy, focal = camera.cx - left, camera.cy - top, camera.focal
    if enlarge:
        scale = width / size[0]
        view = cv2.resize(view, (width, height), interpolation=cv2.INTER_CUBIC)
        cx, cy, focal = (cx + 0.5) * scale - 0.5, (cy + 0.5) * scale - 0.5, focal * scale
    view_height, view_width = view.shape[:2]
    return view, Intrinsics(focal, focal, cx, cy, width=view_width, height=view_height)


def evaluate_telephoto(data: Path, fractions: tuple[float, ...] = TELEPHOTO_FRACTIONS
                       ) -> list[RunResult]:
    """The York photos as a longer lens would have seen them (:func:`telephoto_view`: each
    cropped around its principal point to ``fractions`` of its sides, as cropped and enlarged
    back to 640x480), estimated in this process with the focal length given and measured
    against the same truth: real scenes at 1.5 to 3.2 long sides of focal length, which the
    photos as taken (1.05) do not show."""
    from gsrwt_cli.geometry.camera import Intrinsics

    cv2.setNumThreads(1)
    runs = []
    for fraction in fractions:
        for enlarge in (False, True):
            photos = []
            for image, row in sorted(read_truth(data).items()):
                pixels = cv2.imread(str(data / "images" / image))
                height, width = pixels.shape[:2]
                focal, cx, cy = (float(row[key]) for key in ("focal_px", "cx", "cy"))
                view, camera = telephoto_view(
                    pixels, Intrinsics(focal, focal, cx, cy, width=width, height=height),
                    fraction, enlarge)
                photos.append(_estimated_view(image, row, view, camera))
            long_sides = camera.focal / max(camera.width or 1, camera.height or 1)
            name = (f"{round(width * fraction)}x{round(height * fraction)}"
                    f"{' enlarged' if enlarge else ''} (f {long_sides:.1f} long sides)")
            runs.append(RunResult(name, photos, 0.0, 0.0))
    return runs


def evaluate_altered(data: Path, exif: bool = False) -> list[RunResult]:
    """The York photos as they might reach gsrwt after a messaging app, a noisier sensor, a
    softer lens or another exposure (:data:`ALTERATIONS`), estimated in this process and
    measured against the same truth: the same scenes, pixels that differ as another
    photographer's would. With the calibrated focal length and principal point, or (``exif``)
    as a photographer gives them: the focal length from the photo's EXIF (as ``gsrwt
    estimate`` reads it, refined by the segments), the principal point the image's centre."""
    from gsrwt_cli.geometry.camera import Intrinsics
    from gsrwt_cli.inputs.exif import focal_from_exif

    cv2.setNumThreads(1)
    runs = []
    for name, alter in ALTERATIONS.items():
        photos = []
        for index, (image, row) in enumerate(sorted(read_truth(data).items())):
            path = data / "images" / image
            pixels = cv2.imread(str(path))
            height, width = pixels.shape[:2]
            if exif:
                taken = focal_from_exif(path.read_bytes(), width, height)
                assert taken is not None, f"{image} has no EXIF focal length"
                camera = Intrinsics(taken.fx, taken.fy, (width - 1) / 2, (height - 1) / 2,
                                    width=width, height=height)
            else:
                focal, cx, cy = (float(row[key]) for key in ("focal_px", "cx", "cy"))
                camera = Intrinsics(focal, focal, cx, cy, width=width, height=height)
            photos.append(_estimated_view(image, row, alter(pixels, index), camera, exif))
        runs.append(RunResult(name, photos, 0.0, 0.0))
    return runs


def report_views(runs: list[RunResult], title: str = "York photos shrunk (in process, "
                   "calibrated focal scaled with them)") -> str:
    """The lines of :func:`evaluate_smaller` or :func:`evaluate_telephoto`, as text."""
    lines = [f"{title}: vertical median / p90 / worst | wall normal | refused | confidently "
             "wrong"]
    for run in runs:
        vertical = measure.summarize(p.vertical for p in run.photos)
        wall = measure.summarize(p.wall for p in run.photos)
        wrong = ", ".join(f"{p.image} {p.vertical:.1f}/{p.wall:.1f} ({p.confidence:.2f})"
                          for p in run.confidently_wrong)
        refused = sum(p.status != "ok" for p in run.photos)
        lines.append(f"  {run.name:8s} {vertical.median:5.2f} {vertical.p90:5.2f} "
                     f"{vertical.worst:5.2f} | {wall.median:5.2f} {wall.p90:5.2f} "
                     f"{wall.worst:5.2f} | {refused:2d} of {len(run.photos)} | "
                     f"{len(run.confidently_wrong)}{': ' + wrong if wrong else ''}")
    return "\n".join(lines)


@dataclass
class OtherPhoto:
    """One photo of ``tests/data/real`` (its row of ``photos.csv``) and what ``gsrwt estimate``
    (no focal length) and ``gsrwt rectify --auto`` made of it."""

    image: str
    structure: str
    expected: str
    estimate_status: str
    estimate_confidence: float | None
    estimate_pose: tuple[float, float, float] | None
    estimate_focal: float | None
    true_focal: float | None
    auto_status: str
    auto_confidence: float | None
    auto_pose: tuple[float, float, float] | None
    error: str

    @property
    def wrongly_accepted(self) -> tuple[bool, bool]:
        """(estimate, --auto) gave ``ok`` for a photo that must be refused."""
        refuse = self.expected == "refuse"
        return refuse and self.estimate_status == "ok", refuse and self.auto_status == "ok"


def _pose(row: dict[str, str], *names: str) -> tuple[float, float, float] | None:
    return tuple(float(row[name]) for name in names) if row.get("status") == "ok" else None


def evaluate_other_photos(folder: Path = OTHER_PHOTOS, jobs: int = 1) -> list[OtherPhoto]:
    """``gsrwt estimate`` (no focal length: the photos carry no EXIF) and ``gsrwt rectify
    --auto`` over the photos ``folder/photos.csv`` lists, one subprocess each."""
    with open(folder / "photos.csv", newline="") as file:
        manifest = list(csv.DictReader(file))
    with tempfile.TemporaryDirectory(prefix="gsrwt-real-") as temporary:
        scratch = Path(temporary)
        estimates, _, _ = run_estimate(folder, None, jobs, scratch / "estimate.csv")
        table = scratch / "auto.csv"
        done = subprocess.run(
            [str(GSRWT), "rectify", str(folder), "--auto", "-o", str(scratch / "out"),
             "--table", str(table), "-j", str(jobs), "-q"], capture_output=True, text=True)
        if done.returncode not in (0, 1) or not table.exists():
            raise SystemExit(f"gsrwt rectify --auto failed (exit {done.returncode}): "
                             f"{done.stderr.strip()}")
        with open(table, newline="") as file:
            autos = {Path(row["image"]).name: row for row in csv.DictReader(file)}
    by_image = {Path(row["image"]).name: row for row in estimates}
    photos = []
    for entry in manifest:
        estimate = by_image.get(entry["image"], {"status": "missing"})
        auto = autos.get(entry["image"], {"status": "missing"})
        photos.append(OtherPhoto(
            entry["image"], entry["structure"], entry["expected"], estimate["status"],
            _number(estimate.get("confidence", "")), _pose(estimate, "pan", "tilt", "roll"),
            _number(estimate.get("focal", "")), _number(entry.get("focal_px", "")),
            auto["status"], _number(auto.get("confidence", "")),
            _pose(auto, "pan_deg", "tilt_deg", "roll_deg"),
            estimate.get("error", "") or auto.get("error", "")))
    return photos


#: Focal lengths given to the photos of other kinds, in multiples of each photo's long side: a
#: phone's wide lens (0.8) to a telephoto (4).
FOCAL_FACTORS = (0.8, 1.6, 2.5, 4.0)


@dataclass
class GivenFocalRun:
    """``gsrwt estimate`` over the photos of other kinds, each given ``factor`` times its long
    side as its focal length (in a sidecar, as a photo's EXIF would give it)."""

    factor: float
    wrongly_accepted: list[str]
    planar_ok: list[str]


def evaluate_other_photos_given_focal(folder: Path = OTHER_PHOTOS, jobs: int = 1,
                                      factors: tuple[float, ...] = FOCAL_FACTORS
                                      ) -> list[GivenFocalRun]:
    """One run per focal length factor: which photos that must be refused got ``ok``, and
    which planar ones did."""
    with open(folder / "photos.csv", newline="") as file:
        manifest = list(csv.DictReader(file))
    sides = {}
    for entry in manifest:
        height, width = cv2.imread(str(folder / entry["image"]), cv2.IMREAD_UNCHANGED).shape[:2]
        sides[entry["image"]] = max(width, height)
    runs = []
    with tempfile.TemporaryDirectory(prefix="gsrwt-real-focal-") as temporary:
        scratch = Path(temporary)
        for factor in factors:
            sidecar = scratch / f"focal-{factor:g}.csv"
            with open(sidecar, "w", newline="") as file:
                writer = csv.writer(file)
                writer.writerow(["image", "focal"])
                for image, side in sides.items():
                    writer.writerow([image, f"{factor * side:.1f}"])
            rows, _, _ = run_estimate(folder, sidecar, jobs, scratch / f"{factor:g}.csv")
            status = {Path(row["image"]).name: row["status"] for row in rows}
            runs.append(GivenFocalRun(
                factor,
                [e["image"] for e in manifest
                 if e["expected"] == "refuse" and status.get(e["image"]) == "ok"],
                [e["image"] for e in manifest
                 if e["expected"] == "right" and status.get(e["image"]) == "ok"]))
    return runs


def survey_photos(folder: Path, factors: tuple[float, ...] = FOCAL_FACTORS,
                  long_side: int = 640) -> list[tuple[str, list[str]]]:
    """Any folder of photos whose orientation nobody measured (``*.jpg``, ``*.jpeg``,
    ``*.png`` in it and below): each shrunk as ``tests/data/real`` is (area averaging) to a
    long side of at most ``long_side`` pixels, then estimated in this process with no focal
    length and with ``factors`` times its long side, given alone (each checked for a lens, as
    ``gsrwt estimate`` checks a photo with no camera or a focal length alone): per photo,
    the runs that gave a pose (``none``, ``0.8`` ...) with its confidence and pan, tilt,
    roll. For photos that must be refused (no man-made structure), every such run is a
    confidently wrong result to look at."""
    from gsrwt_cli.api.estimate import DEFAULT_MIN_CONFIDENCE, detect_segments, estimate_pose
    from gsrwt_cli.api.lens_lines import checked_for_a_lens
    from gsrwt_cli.geometry.camera import Intrinsics

    sys.path.insert(0, str(OTHER_PHOTOS))
    from make_real_photos import shrunk

    cv2.setNumThreads(1)
    found = []
    for path in sorted(p for p in folder.rglob("*") if p.suffix.lower() in
                       (".jpg", ".jpeg", ".png")):
        pixels = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if pixels is None:
            continue
        pixels = shrunk(pixels, long_side)
        height, width = pixels.shape[:2]
        lines = detect_segments(pixels)
        accepted = []
        for factor in (None, *factors):
            focal = None if factor is None else factor * max(width, height)
            camera = None if focal is None else Intrinsics(
                focal, focal, (width - 1) / 2, (height - 1) / 2, width=width, height=height)
            estimate = checked_for_a_lens(pixels, estimate_pose(pixels, camera, lines=lines),
                                          camera=camera)
            if estimate.error is None and estimate.confidence >= DEFAULT_MIN_CONFIDENCE:
                pose = estimate.pose
                accepted.append(f"{'none' if factor is None else f'{factor:g}'}: "
                                f"{estimate.confidence:.2f} ({pose.pan:.1f} {pose.tilt:.1f} "
                                f"{pose.roll:.1f})")
        found.append((str(path.relative_to(folder)), accepted))
    return found


def report_given_focal(runs: list[GivenFocalRun], photos: list[OtherPhoto]) -> str:
    """The lines of :func:`evaluate_other_photos_given_focal`, as text."""
    must_refuse = sum(p.expected == "refuse" for p in photos)
    planar = sum(p.expected == "right" for p in photos)
    lines = ["the same photos given a focal length (a sidecar, factor x each photo's long "
             "side, as EXIF would give it):"]
    for run in runs:
        wrong = ", ".join(run.wrongly_accepted) or "none"
        lines.append(f"  {run.factor:3g} x long side: must be refused but ok "
                     f"{len(run.wrongly_accepted)} of {must_refuse} ({wrong}); planar photos ok "
                     f"{len(run.planar_ok)} of {planar} ({', '.join(run.planar_ok) or 'none'})")
    return "\n".join(lines)


def report_other_photos(photos: list[OtherPhoto]) -> str:
    """The table of :func:`evaluate_other_photos`, as text."""
    must_refuse = [p for p in photos if p.expected == "refuse"]
    planar = [p for p in photos if p.expected == "right"]
    lines = [
        f"other real photos ({OTHER_PHOTOS.relative_to(REPOSITORY)}, no focal length): "
        f"{len(must_refuse)} must be refused, {len(planar)} have planar structure",
        f"  must be refused but ok: estimate {sum(p.wrongly_accepted[0] for p in photos)}, "
        f"--auto {sum(p.wrongly_accepted[1] for p in photos)} of {len(must_refuse)}; "
        f"planar photos ok: estimate {sum(p.estimate_status == 'ok' for p in planar)}, "
        f"--auto {sum(p.auto_status == 'ok' for p in planar)} of {len(planar)}",
        "  photo              expected | estimate: status conf   pan  tilt  roll  focal "
        "| rectify --auto: status conf   pan  tilt  roll",
    ]
    for p in photos:
        pose = (" ".join(f"{angle:5.1f}" for angle in p.estimate_pose) if p.estimate_pose
                else " " * 17)
        auto = " ".join(f"{angle:5.1f}" for angle in p.auto_pose) if p.auto_pose else ""
        focal = _format(p.estimate_focal, 0) + (f" (true {p.true_focal:.0f})"
                                                 if p.true_focal else "")
        lines.append(
            f"  {p.image:18s} {p.expected:8s} | {p.estimate_status:6s} "
            f"{_format(p.estimate_confidence):>4s} {pose} {focal:>5s} | {p.auto_status:6s} "
            f"{_format(p.auto_confidence):>4s} {auto}")
    return "\n".join(lines)


@dataclass
class BoardPhoto:
    """One chessboard photo and what ``gsrwt estimate`` (its calibration given) made of it:
    status, confidence and the errors against the board (:func:`measure.board_errors`)."""

    image: str
    status: str
    confidence: float | None
    vertical: float
    wall: float
    error: str

    @property
    def confidently_wrong(self) -> bool:
        return measure.is_confidently_wrong(self.status == "ok",
                                            measure.ImageErrors(self.vertical, self.wall))


#: OpenCV's two webcams of its stereo sample: the folder of each one's photos (with its
#: ``right_poses.csv`` or ``left_poses.csv``) and its calibration file.
BOARD_CAMERAS = {"right": (BOARDS, BOARDS / "right_camera.yml"),
                 "left": (BOARDS / "left", BOARDS / "opencv4_left_intrinsics.yml")}


def evaluate_chessboards(folder: Path | None = None, jobs: int = 1, calibrated: bool = True,
                         camera: str = "right") -> list[BoardPhoto]:
    """``gsrwt estimate`` over OpenCV's chessboard photos of one webcam (``right*.jpg`` or
    ``left/left*.jpg``; ``folder``: others of the same names) with its calibration file
    (:data:`BOARD_CAMERAS`), or with no camera at all (``calibrated`` False: the focal
    length estimated, and the lens, a wide angle of k1 -0.30 or -0.27, unknown), each
    board's plane taken as the wall and measured against its pose (``right_poses.csv``,
    ``left_poses.csv``)."""
    own_folder, calibration = BOARD_CAMERAS[camera]
    folder = own_folder if folder is None else folder
    with open(folder / f"{camera}_poses.csv", newline="") as file:
        poses = {row["image"]: [float(row[f"rvec_{c}"]) for c in "xyz"]
                 for row in csv.DictReader(file)}
    with tempfile.TemporaryDirectory(prefix="gsrwt-boards-") as temporary:
        rows, _, _ = run_estimate([folder / image for image in poses], None, jobs,
                                  Path(temporary) / "estimate.csv",
                                  camera=calibration if calibrated else None)
    photos = []
    for row in rows:
        image = Path(row["image"]).name
        directions = (measure.directions_from_pose(*_pose(row, "pan", "tilt", "roll"))
                      if row["status"] == "ok" else None)
        errors = measure.board_errors(directions, poses[image])
        photos.append(BoardPhoto(image, row["status"], _number(row.get("confidence", "")),
                                 errors.vertical, errors.wall, row.get("error", "")))
    return photos


def report_chessboards(photos: list[BoardPhoto], calibrated: bool = True,
                       camera: str = "right") -> str:
    """The lines of :func:`evaluate_chessboards`, as text."""
    ok = [p for p in photos if p.status == "ok"]
    vertical = measure.summarize(p.vertical for p in ok)
    wall = measure.summarize(p.wall for p in ok)
    given = ("calibration given" if calibrated else
             "no calibration: focal length estimated, the lens unknown")
    where = "right*.jpg" if camera == "right" else "left/left*.jpg"
    lines = [f"chessboard photos (tests/data/{where}, {given}; the board's plane as "
             f"the wall, its pose by cv2.solvePnP): {len(ok)} of {len(photos)} ok, "
             f"{sum(measure.is_within(measure.ImageErrors(p.vertical, p.wall)) for p in ok)} "
             f"of them within 2 deg, confidently wrong: "
             f"{', '.join(p.image for p in photos if p.confidently_wrong) or 'none'}",
             f"  over the ok: vertical {_format(vertical.median)} / {_format(vertical.p90)} / "
             f"{_format(vertical.worst)}, wall {_format(wall.median)} / {_format(wall.p90)} / "
             f"{_format(wall.worst)}"]
    for p in photos:
        lines.append(f"  {p.image:12s} {p.status:6s} {_format(p.confidence):>4s} vertical "
                     f"{_format(p.vertical):>6s} wall {_format(p.wall):>6s}")
    return "\n".join(lines)


def _format(value: float, digits: int = 2) -> str:
    return "-" if value is None or math.isnan(value) else f"{value:.{digits}f}"


def report(runs: list[RunResult], data: Path, jobs: int, in_process_ms: float) -> str:
    """The table, as text."""
    count = len(runs[0].photos)
    lines = [
        f"gsrwt estimate on {count} real photos, York Urban DB training half ({data})",
        f"{datetime.date.today()}, {platform.node()}: {_cpu_name()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, -j {jobs}",
        "",
        "errors in degrees (no estimate = 90)  vertical: median  p90  worst | wall normal: "
        "median  p90  worst | refused | confidently wrong (ok, > 3 deg) | ms per photo: CPU  "
        "wall",
    ]
    for run in runs:
        lines.append(
            f"  {run.name:34s}  {_format(run.vertical.median):>6s} {_format(run.vertical.p90):>5s}"
            f" {_format(run.vertical.worst):>6s} | {_format(run.wall.median):>6s} "
            f"{_format(run.wall.p90):>5s} {_format(run.wall.worst):>6s} | "
            f"{len(run.refused):3d} of {count} | {len(run.confidently_wrong):3d} | "
            f"{1000 * run.cpu_seconds / count:6.1f} {1000 * run.wall_seconds / count:6.1f}")
    lines.append(f"the estimate alone, in one process, calibrated focal (photos decoded, OpenCV "
                 f"on one thread, quickest of {IN_PROCESS_PASSES} passes): {in_process_ms:.1f} ms "
                 "of CPU per photo (issue 23: no slower than about 25)")
    for run in runs:
        focal = run.focal_errors()
        if not math.isnan(focal.median):
            lines.append(f"focal length error, {run.name} (estimated or refined, ok): median "
                         f"{focal.median:.1f} %, p90 {focal.p90:.1f} %, worst {focal.worst:.1f} %")
    lines += ["", "confidence calibration (status ok): per bin, photos and the fraction within "
              f"{measure.WITHIN_DEG:g} deg on both measures"]
    lines.append("  confidence   " + "".join(f"| {run.name:<29s} " for run in runs))
    for bins in zip(*(run.calibration() for run in runs)):
        low, high = bins[0].low, bins[0].high
        cells = "".join(
            f"| n {b.count:3d}, mean {_format(b.mean_confidence):>4s}, within "
            f"{_format(b.fraction_within):>4s} "
            for b in bins)
        lines.append(f"  {low:.1f}-{high:.1f}      {cells}")
    for run in runs:
        for label, photos in (("refused", run.refused),
                              ("confidently wrong", run.confidently_wrong)):
            for p in photos:
                lines.append(
                    f"{run.name}, {label}: {p.image} vertical {p.vertical:.2f}, wall "
                    f"{p.wall:.2f}, confidence {_format(p.confidence)}, focal "
                    f"{_format(p.focal, 0)} ({p.focal_source or '-'})"
                    + (f": {p.error}" if p.error else ""))
    return "\n".join(lines)


def as_json(runs: list[RunResult], data: Path, jobs: int, in_process_ms: float) -> dict:
    """Everything of :func:`report`, and each photo's row, for machines."""
    count = len(runs[0].photos)
    return {
        "data": str(data), "date": str(datetime.date.today()), "machine": platform.node(),
        "cpu": _cpu_name(), "cores": os.cpu_count(), "jobs": jobs, "photos": count,
        "estimate_cpu_ms_in_process": in_process_ms,
        "runs": [{
            "name": run.name,
            "vertical": run.vertical._asdict(), "wall": run.wall._asdict(),
            "refused": len(run.refused), "confidently_wrong": len(run.confidently_wrong),
            "focal_error_percent": run.focal_errors()._asdict(),
            "cpu_ms_per_photo": 1000 * run.cpu_seconds / count,
            "wall_ms_per_photo": 1000 * run.wall_seconds / count,
            "calibration": [b._asdict() for b in run.calibration()],
            "per_photo": [asdict(p) for p in run.photos],
        } for run in runs],
    }


def _no_nan(value: object) -> object:
    """``value`` with every NaN (an empty bin, no estimated focal) as None: JSON has no NaN."""
    if isinstance(value, float) and math.isnan(value):
        return None
    if isinstance(value, dict):
        return {key: _no_nan(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_no_nan(item) for item in value]
    return value


def _cpu_name() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA,
                        help="the york-urban-train folder (truth.csv, images/)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of the table")
    parser.add_argument("--jobs", type=int, default=1, help="gsrwt estimate's -j (default 1)")
    parser.add_argument("--survey", type=Path, metavar="FOLDER",
                        help="only estimate every photo in FOLDER (no focal length, then "
                             "0.8 to 4 long sides) and list those that get a pose")
    parser.add_argument("--long-side", type=int, default=640,
                        help="--survey: shrink each photo to this long side first (640)")
    parser.add_argument("--two-directions", action="store_true",
                        help="also the York photos with one horizontal direction's edges left "
                             "out (about a minute more)")
    parser.add_argument("--smaller", action="store_true",
                        help="also the York photos shrunk to 480x360 and 320x240")
    parser.add_argument("--telephoto", action="store_true",
                        help="also the York photos cropped around their principal point, as "
                             "a longer lens would have seen them")
    parser.add_argument("--altered", action="store_true",
                        help="also the York photos re-encoded, noisier, blurred, brightened "
                             "and darkened")
    arguments = parser.parse_args()
    if arguments.survey is not None:
        surveyed = survey_photos(arguments.survey, long_side=arguments.long_side)
        for name, accepted in surveyed:
            if accepted:
                print(f"{name}: {'; '.join(accepted)}")
        print(f"{sum(bool(a) for _, a in surveyed)} of {len(surveyed)} photos got a pose in "
              f"some run (no focal length, or {', '.join(f'{f:g}' for f in FOCAL_FACTORS)} "
              "times the long side)")
        return
    data = arguments.data
    if not (data / "truth.csv").is_file() or not (data / "images").is_dir():
        parser.exit(2, f"bench_real_photos: no York Urban data at {data} (needs truth.csv and "
                       "images/); give its path as the first argument\n")
    runs = evaluate(data, arguments.jobs)
    in_process_ms = estimate_cpu_ms(data)
    others = evaluate_other_photos(OTHER_PHOTOS, arguments.jobs)
    given_focal = evaluate_other_photos_given_focal(OTHER_PHOTOS, arguments.jobs)
    boards = {(camera, calibrated): evaluate_chessboards(None, arguments.jobs, calibrated,
                                                         camera)
              for camera in BOARD_CAMERAS for calibrated in (True, False)}
    if arguments.json:
        result = as_json(runs, data, arguments.jobs, in_process_ms)
        result["other_photos"] = [asdict(p) for p in others]
        result["other_photos_given_focal"] = [asdict(run) for run in given_focal]
        result["chessboards"] = [asdict(p) for p in boards["right", True]]
        result["chessboards_uncalibrated"] = [asdict(p) for p in boards["right", False]]
        result["left_chessboards"] = [asdict(p) for p in boards["left", True]]
        result["left_chessboards_uncalibrated"] = [asdict(p) for p in boards["left", False]]
        if arguments.two_directions:
            result["two_directions"] = [
                {"name": run.name, "photos": [asdict(p) for p in run.photos]}
                for run in evaluate_two_directions(data)]
        print(json.dumps(_no_nan(result), indent=1, allow_nan=False))
    else:
        print(report(runs, data, arguments.jobs, in_process_ms))
        print()
        print(report_other_photos(others))
        print(report_given_focal(given_focal, others))
        print()
        for (camera, calibrated), photos in boards.items():
            print(report_chessboards(photos, calibrated, camera))
    if arguments.two_directions and not arguments.json:
        print()
        print(report_two_directions(evaluate_two_directions(data)))
    if arguments.smaller and not arguments.json:
        print()
        print(report_views(evaluate_smaller(data)))
    if arguments.telephoto and not arguments.json:
        print()
        print(report_views(evaluate_telephoto(data), "York photos as a longer lens would "
                             "have seen them (in process, calibrated focal)"))
    if arguments.altered and not arguments.json:
        print()
        print(report_views(evaluate_altered(data), "York photos altered (in process, "
                                                   "calibrated focal)"))
        print(report_views(evaluate_altered(data, exif=True), "... as a photographer gives "
                                                              "them (EXIF focal, refined)"))


if __name__ == "__main__":
    main()
