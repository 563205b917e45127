"""``gsrwt rectify``: canonical frontal views of whole directories, and a table of what was done.

The command reads in four steps: its options into the objects the layers below take
(:func:`settings_from_options`, :func:`table_from_options`, :class:`RunOptions`), every check
before any image is read (:func:`plan_batch`), the run with its table (:func:`run_planned`),
and the summary line.

Over 400 lines: the main command's options, its checks before any work, and the wording of
the core's errors in terms of those options.
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
import os
import sys
from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path, PurePosixPath
from typing import Any

import click

from ..api.estimate import DEFAULT_MIN_CONFIDENCE, WALL_CHOICES
from ..base.messages import one_line, quote
from ..base.numerals import parse_decimal, parse_whole
from ..batch.estimate_jobs import AUTO_MODES, EstimateOptions
from ..batch.rectify_jobs import (
    RECTIFY_COLUMNS,
    Counts,
    ImageWorker,
    Job,
    Settings,
    dead_worker_row,
    job_for_elsewhere,
    plan_jobs,
    remove_temporaries_left,
    row_for_here,
    run_batch,
    settings_for_elsewhere,
    worker_context,
)
from ..batch.video_jobs import CODEC_CHOICES as VIDEO_CODEC_CHOICES
from ..batch.video_jobs import DEFAULT_MAX_POSE_GAP
from ..batch.video_jobs import TIME_MODES as VIDEO_TIME_MODES
from ..geometry.framing import (
    DEFAULT_MAX_AREA,
    EmptyOutputError,
    FrameOutsideImageError,
    Framing,
    MissingDistanceError,
    NothingWithinStretchError,
    OutputTooLargeError,
)
from ..imaging.images import (
    ImageFormatError,
    canonical_extension,
    check_writable,
)
from ..inputs.calibration import CalibrationError
from ..inputs.guides import parse_aspect
from ..inputs.records import load_camera_file
from ..inputs.sources import (
    Source,
    source_from_listed_path,
    sources_from_directory,
    sources_from_location,
)
from ..inputs.videos import is_video_name
from ..io.outputs import remove_stale_temporaries
from ..io.storage import Location, location
from ..io.targets import file_identity, protected_files
from ..tables.shards import parse_shard, shard_slice, shard_table_name
from ..tables.writer import format_from_extension, read_table
from .bags import BagOptions, is_bag_input
from .batch_run import (  # noqa: F401  (named here too: estimate and the tests take them)
    TableWriteError,
    Terminated,
    end_batch,
    open_table,
    progress_bar,
    recorded_rows,
    stop_on_signals,
)
from .options import (
    InputError,
    Integer,
    Number,
    PathOrUrl,
    auto_mode_command,
    check_lens_profile,
    guide_options,
    interpolation_option,
    jobs_option,
    lens_from_lines_option,
    lens_profile_option,
    load_sidecar_option,
    max_input_pixels_option,
    orientation_option,
    prepare_directory,
    prepare_table,
    quality_option,
    quiet_option,
    view_defaults,
    view_options,
)


def parse_crop_aspect(text: str | None, bbox: object) -> float | str | None:
    """``--crop-aspect``: ``original``, ``W:H`` or one positive number (width over height);
    only with ``--bbox crop``."""
    if text is None:
        return None
    if bbox != "crop":
        raise click.UsageError("--crop-aspect goes with --bbox crop")
    if text.strip().lower() == "original":
        return "original"
    try:
        return parse_aspect(text)
    except ValueError as error:
        raise click.BadParameter(str(error), param_hint="'--crop-aspect'") from None


def parse_bbox(text: str) -> str | tuple[float, float, float, float]:
    """``frontal``, ``full``, ``crop``, ``corners`` or ``X0,Y0,X1,Y1`` (default-frame
    pixels, X1 > X0, Y1 > Y0)."""
    if text in ("frontal", "full", "crop", "corners"):
        return text
    parts = text.split(",")
    try:
        box = tuple(parse_decimal(p) for p in parts)
    except ValueError:
        box = ()
    if len(box) != 4 or not all(math.isfinite(v) for v in box):
        raise click.BadParameter(
            f"expected frontal, full, crop or X0,Y0,X1,Y1 (four numbers), or corners; got "
            f"{quote(text)}",
            param_hint="'--bbox'",
        )
    if box[2] <= box[0] or box[3] <= box[1]:
        raise click.BadParameter(f"X1 must exceed X0 and Y1 must exceed Y0, got {text}",
                                 param_hint="'--bbox'")
    return box  # type: ignore[return-value]


def parse_pixel_count(text: str, option: str) -> float:
    """``50M``, ``2.5e6`` or ``800K`` pixels (ASCII digits)."""
    factor = {"k": 1e3, "m": 1e6, "g": 1e9}.get(text[-1:].lower(), 1.0)
    number = text[:-1] if factor != 1.0 else text
    try:
        value = parse_decimal(number) * factor
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or value < 1:
        raise click.BadParameter(f"expected a pixel count such as 50M, got {quote(text)}",
                                 param_hint=f"'{option}'")
    return value


def parse_size(text: str) -> tuple[int, int]:
    """``1920x1080``: a width and height of whole positive pixels (ASCII digits)."""
    parts = text.lower().split("x")
    try:
        width, height = (parse_whole(part) for part in parts)
    except ValueError:
        width = height = 0
    if len(parts) != 2 or width < 1 or height < 1 or max(width, height) > 1 << 30:
        raise click.BadParameter(f"expected WIDTHxHEIGHT in pixels such as 1920x1080, got "
                                 f"{quote(text)}", param_hint="'--max-size'")
    return width, height


def positive(name: str, value: float | None) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise click.BadParameter(f"must be a positive number, got {value:g}",
                                 param_hint=f"'{name}'")


def collect_sources(inputs: tuple[str, ...], recursive: bool) -> tuple[list[Source], list[str]]:
    """Image files, directories and ``-`` (paths on standard input) to sources.

    Paths on standard input are read as bytes and decoded as the file system does, so a
    name that is not UTF-8 still names its file. Returns the sources and the problems met in
    subdirectories (with ``-r``); a missing or unreadable INPUT is an :class:`InputError`.
    """
    sources: list[Source] = []
    unreadable: list[str] = []
    for text in inputs:
        if text == "-":
            data = click.get_binary_stream("stdin").read()
            names = [os.fsdecode(line.strip()) for line in data.split(b"\n")]
            sources += [source_from_listed_path(name) for name in names if name]
            continue
        path = location(text)
        if isinstance(path, Location):
            sources += sources_at_url(text, path, recursive, unreadable)
        elif path.is_dir():
            try:
                sources += sources_from_directory(path, recursive, unreadable)
            except OSError as error:
                raise InputError(f"{text}: cannot read directory ({error.strerror})") from None
        elif path.exists():
            sources.append(Source(path, PurePosixPath(path.name)))
        else:
            raise InputError(f"{text}: no such file or directory")
    return sources, unreadable


def sources_at_url(text: str, url: Location, recursive: bool,
                   unreadable: list[str] | None = None) -> list[Source]:
    """The image a URL names, or the images below it (one listing; keys that name no path
    reported in ``unreadable``), or an InputError."""
    try:
        if url.is_file():
            return [Source(url, PurePosixPath(url.name))]
        found = sources_from_location(url, recursive, unreadable)
    except (OSError, ValueError) as error:
        reason = error.strerror if isinstance(error, OSError) and error.strerror else error
        raise InputError(f"{text}: cannot read ({one_line(str(reason), 200)})") from None
    if not found and not url.exists():
        raise InputError(f"{text}: no such file or directory")
    return found


def refuse_unsafe_outputs(
    inputs: tuple[str, ...], sources: list[Source], outputs: list[Path | Location],
    outdir: Path | Location, recursive: bool, table: Path | Location | None,
    sidecar: Path | Location | None,
) -> None:
    """Refuse, before writing anything, a run that could overwrite what the user gave us
    (local paths or URLs alike)."""
    if isinstance(outdir, Path) and outdir.exists() and not outdir.is_dir():
        raise InputError(f"-o {outdir}: exists and is not a directory")
    given = protected_files(s.path for s in sources)
    for source, output in zip(sources, outputs):
        if file_identity(output) in given:
            raise InputError(
                f"-o {outdir}: output {output} would overwrite the input {source.path}; "
                "choose another output directory"
            )
    if recursive:
        real_outdir = file_identity(outdir)
        for text in inputs:
            given_input = location(text) if text != "-" else None
            if given_input is not None and (isinstance(given_input, Location)
                                            or given_input.is_dir()):
                real_input = file_identity(given_input)
                separator = "/" if isinstance(given_input, Location) else os.sep
                if real_outdir == real_input or real_outdir.startswith(real_input + separator):
                    raise InputError(
                        f"-o {outdir}: is inside the input directory {text}, where a later "
                        "--recursive run would take outputs for inputs; choose another"
                    )
    if table is not None and file_identity(table) in given | protected_files([sidecar]):
        raise InputError(f"--table {table}: would overwrite an input; choose another path")


def previous_rows(path: str, fmt: str) -> dict[tuple[str, str], dict[str, Any]]:
    """The last run's table at ``path``, by ``(image, output)``; empty if there is none."""
    try:
        table = location(path)
        if isinstance(table, Location):
            text = table.read_bytes().decode("utf-8", "surrogateescape")
            rows = read_table(io.StringIO(text, newline=""), fmt)
        else:
            with open(table, encoding="utf-8", errors="surrogateescape", newline="") as stream:
                rows = read_table(stream, fmt)
    except (OSError, ValueError, csv.Error):
        return {}
    return {
        (str(row.get("image")), str(row.get("output"))): row
        for row in rows if row.get("image") is not None and row.get("output") is not None
    }


def megapixels(pixels: int) -> str:
    """A pixel count in megapixels, with the digits that show it (0.0075, 30.7)."""
    value = pixels / 1e6
    return f"{value:.1f}" if value >= 0.1 else f"{value:.2g}"


def either(remedies: list[str]) -> str:
    """``a, b or c``."""
    return " or ".join(filter(None, [", ".join(remedies[:-1]), remedies[-1]]))


@dataclass(frozen=True)
class RectifyWording:
    """Words the core's errors in terms of one ``gsrwt rectify`` run's options, naming only
    remedies not already in use (an instance is :class:`~gsrwt_cli.batch.rectify_jobs.Settings`'s
    ``describe``; it is pickled to the workers).

    ``bbox``: frontal, full, crop, or box (X0,Y0,X1,Y1); ``metric``: the scale comes from
    --px-per-unit; ``max_size``: --max-size is given.
    """

    bbox: str = "frontal"
    metric: bool = False
    max_size: bool = False

    def __call__(self, error: BaseException) -> str | None:
        """``error`` in the run's terms, or None for its own text."""
        if isinstance(error, OutputTooLargeError):
            return (f"the output would be {error.width}x{error.height} = "
                    f"{megapixels(error.width * error.height)} megapixels, above --max-pixels "
                    f"{error.limit / 1e6:g} megapixels; use {self._smaller_output()}")
        if isinstance(error, EmptyOutputError):
            return (f"the output would be empty ({error.width}x{error.height} pixels); use "
                    f"{self._larger_output()}")
        if isinstance(error, NothingWithinStretchError):
            return self._nothing_within(error)
        if isinstance(error, FrameOutsideImageError):
            if error.beyond_horizon:
                return ("no part of the image is in front of the vanishing line; check the "
                        "pose and the principal point")
            if self.bbox == "box":
                return ("no pixel of --bbox has a source in the image: the box lies where the "
                        "image does not see the wall; choose one within --bbox full's frame")
            if self.bbox == "frontal":
                return ("no pixel of the frontal frame (--bbox frontal, around where the "
                        "optical axis meets the wall) has a source in the image; check the "
                        "pose and the principal point, or frame what it sees with --bbox "
                        "full")
            return None
        if isinstance(error, MissingDistanceError):
            return ("--px-per-unit needs the camera-to-wall 'distance' of the image; give it "
                    "(--distance or a 'distance' column) or use --scale")
        if isinstance(error, ImageFormatError) and error.alternatives:
            return f"{error.reason}; use --ext {' or --ext '.join(error.alternatives)}"
        return None

    def _smaller_output(self) -> str:
        remedies = ["a smaller --max-size" if self.max_size else "--max-size WxH",
                    "a smaller --px-per-unit" if self.metric else "a smaller --scale"]
        if self.bbox in ("full", "crop"):
            remedies += ["a lower --max-stretch", "--bbox frontal"]
        elif self.bbox == "box":
            remedies.append("a smaller --bbox")
        return either([*remedies, "a higher --max-pixels"])

    def _larger_output(self) -> str:
        remedies = ["a larger --px-per-unit" if self.metric else "a larger --scale"]
        if self.max_size:
            remedies.append("a larger --max-size")
        if self.bbox in ("full", "crop"):
            remedies.append("a higher --max-stretch")
        elif self.bbox == "box":
            remedies.append("a larger --bbox")
        return either(remedies)

    @staticmethod
    def _nothing_within(error: NothingWithinStretchError) -> str:
        stretch = f"--max-stretch {error.max_stretch:g}"
        if error.reason == NothingWithinStretchError.BEYOND_HORIZON:
            return ("no part of the image is in front of the vanishing line; check the pose "
                    "and the principal point")
        if error.reason == NothingWithinStretchError.NO_RECTANGLE:
            return (f"--bbox crop finds no rectangle without fill within {stretch}; raise "
                    "--max-stretch, or use --bbox full")
        below_one = (" (below 1, the principal point itself is beyond it)"
                     if error.max_stretch < 1 else "")
        return (f"no part of the image is within {stretch} (every visible pixel is magnified "
                f"more than {error.max_stretch:g} times as much as the principal point); "
                f"raise --max-stretch{below_one}, or use --bbox frontal")


@contextlib.contextmanager
def dask_executor(address: str, processes: int, retries: int,
                  settings: Settings) -> Iterator[Any]:
    """A :class:`~gsrwt_cli.batch.dask_executor.DaskExecutor` on the scheduler at ``address``
    (``local``: a local cluster of ``processes`` workers), or an :class:`InputError` saying
    how to install Dask or that the scheduler cannot be reached."""
    # Workers inherit it. Critical, not error: a worker whose heartbeat meets the cluster
    # closing after Ctrl-C logs that at ERROR with a traceback (distributed's own race);
    # what a user needs to know about a worker arrives as a row or as our one line.
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "critical")
    try:
        from ..batch import dask_executor as engine
    except ImportError as error:
        raise InputError(f"--scheduler {address}: needs Dask ({error.msg}); install it with "
                         "pip install 'gsrwt[dask]'") from None
    try:
        with engine.connect(address, processes, retries) as client:
            yield engine.DaskExecutor(
                client, ImageWorker.in_own_process,
                (settings_for_elsewhere(settings), 1 if processes > 1 else 0),
                on_death=lambda job, reason: dead_worker_row(job, reason, settings),
                on_close=remove_temporaries_left, retries=retries,
                send=job_for_elsewhere, receive=row_for_here,
            )
    except engine.SchedulerError as error:
        raise InputError(f"--scheduler {address}: {error}") from None


@click.command(cls=auto_mode_command(AUTO_MODES))
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...")
@click.option("-o", "--output", "outdir", required=True, type=PathOrUrl(),
              help="Output directory (created if needed), or a URL prefix (s3://bucket/out/).")
@click.option("-r", "--recursive", is_flag=True,
              help="Descend into directories and mirror their tree under OUTDIR.")
@click.option("--sidecar", type=PathOrUrl(dir_okay=False),
              help="CSV or YAML of per-image parameters (rows match by relative path or name); "
                   "a path, a URL, or - for standard input.")
@view_options
@guide_options
@click.option("--bbox", default=None,
              help="Output extent: frontal (the thesis's box, the input's size), full (the "
                   "visible wall, up to --max-stretch), crop (the largest rectangle of it with "
                   "no fill), corners (the rectangle of --corners, at a resolution that keeps "
                   "its pixels) or X0,Y0,X1,Y1 in frontal-frame pixels.  [default: full for a "
                   "still photo whose pose the photo gives (--auto, guides), frontal for a pose "
                   "given and for videos and bags]")
@click.option("--margin", type=Number(min=0), default=0.0, show_default=True,
              help="With --bbox corners: room around the rectangle, in percent of its width "
                   "and height.")
@click.option("--crop-aspect", default=None, metavar="original|W:H",
              help="With --bbox crop: the largest rectangle of this shape instead of any: "
                   "original (the input's width over height), W:H or one number.")
@click.option("--max-stretch", type=Number(), default=4.0, show_default=True,
              help="With --bbox full or crop: stop where the image is magnified more than "
                   "this many times the magnification at its centre.")
@click.option("--scale", type=Number(), default=None,
              help="Output pixels per frontal pixel [default: 1, lowered until the output "
                   "has at most twice the input's pixels].")
@click.option("--px-per-unit", type=Number(), default=None,
              help="Metric output: pixels per unit of the image's 'distance'.")
@click.option("--max-pixels", default="50M", show_default=True,
              help="Refuse an output image larger than this (e.g. 50M, 2e7).")
@click.option("--max-size", default=None, metavar="WxH",
              help="Lower the scale so that the output fits in WxH pixels (the table's "
                   "'scale' says what was used), instead of a larger output.")
@max_input_pixels_option
@orientation_option
@lens_profile_option
@lens_from_lines_option
@interpolation_option
@click.option("--fill", type=Number(), default=0.0, show_default=True,
              help="Value of pixels with no source, in the image's units (0-255, 0-65535).")
@click.option("--antialias/--no-antialias", default=True, show_default=True,
              help="Area-filter where the output shrinks the input (an output pixel over 1.5 "
                   "input pixels), so that fine detail does not alias; below scale 1 a JPEG "
                   "is then decoded 2, 4 or 8 times smaller where every output pixel spans "
                   "that many input pixels.")
@click.option("--alpha", is_flag=True,
              help="Make pixels with no source transparent (adds an alpha channel).")
@click.option("--ext", default=None,
              help="Write this format (jpg, png, tif, webp, bmp) [default: the input's].")
@quality_option
@click.option("--strip-metadata", is_flag=True,
              help="Write the pixels only: without the input's EXIF (camera, lens, date, "
                   "GPS, exposure) and gsrwt's record in XMP, which JPEG, PNG, WebP and TIFF "
                   "outputs otherwise carry (the table's 'metadata' says).")
@click.option("--table", "table_path", default=None,
              help="Where to write the table (.csv, .tsv, .json, .jsonl; - for stdout) "
                   "[default: OUTDIR/gsrwt.csv].")
@jobs_option
@click.option("--overwrite", is_flag=True, help="Replace existing outputs instead of skipping.")
@click.option("--dry-run", is_flag=True,
              help="Check everything and write the table only (status `planned`).")
@click.option("--scheduler", default=None, metavar="ADDRESS", envvar="DASK_SCHEDULER_ADDRESS",
              help="Run the images as tasks of a Dask cluster: its scheduler's address "
                   "(tcp://HOST:8786), or local for a local cluster of -j worker processes "
                   "[default: $DASK_SCHEDULER_ADDRESS, else worker processes here]. Needs "
                   "pip install 'gsrwt[dask]'.")
@click.option("--retries", type=Integer(min=0), default=2, show_default=True,
              help="With --scheduler: times a task is run again when it fails or its "
                   "worker dies (the local cluster's; a remote scheduler keeps its own "
                   "allowed-failures).")
@click.option("--shard", default=None, metavar="K/N",
              help="Process only the K-th of N equal slices of the input list (Slurm array "
                   "jobs, CI matrices); K and N in ASCII digits, 1 <= K <= N <= 1000000; the "
                   "table is OUTDIR/gsrwt.K-of-N.csv; join the tables with 'gsrwt tables "
                   "merge'.")
@quiet_option("No progress bar and no summary.")
@click.option("--auto", type=click.Choice(AUTO_MODES), default=None,
              help="Estimate the pose of images that no source gives pan and tilt for: "
                   "'--auto' or '--auto lines' from their own lines (as 'gsrwt estimate'; "
                   "the focal length too if unknown); '--auto document' from the corners of "
                   "the largest clear quadrilateral of strong edges (a page, a sign, a "
                   "screen), refused when there is none (with --bbox corners: the document "
                   "alone).")
@click.option("--min-confidence", type=Number(0, 1), default=DEFAULT_MIN_CONFIDENCE,
              show_default=True,
              help="With --auto: estimates less confident than this are errors (as "
                   "'gsrwt estimate': the chance, 0-1, that the pose is within 2 degrees).")
@click.option("--wall", type=click.Choice(WALL_CHOICES), default="dominant", show_default=True,
              help="With --auto: the wall to rectify is the vertical plane with the most "
                   "horizontal edges (the surface the photo shows) or the most frontal one "
                   "(|pan| <= 45, as 'gsrwt estimate' reports poses).")
@click.option("--poses", default=None, type=click.Path(dir_okay=False),
              help="A video's poses: a CSV or YAML file of a time and a pose per row (time "
                   "in seconds; pan, tilt, roll or qw, qx, qy, qz; focal, cx, cy may be "
                   "columns), interpolated to each frame (slerp). INPUT is then one video "
                   "(mp4, mkv, avi, mov, webm, m4v; needs pip install 'gsrwt[video]').")
@click.option("--time", "time_mode", type=click.Choice(VIDEO_TIME_MODES), default="relative",
              show_default=True,
              help="With --poses: the time column counts seconds from the first frame, or "
                   "is on the input's own clock (absolute: a video's pts x time_base, a "
                   "bag's header stamps in seconds).")
@click.option("--max-pose-gap", type=Number(min=0), default=DEFAULT_MAX_POSE_GAP,
              show_default=True,
              help="With --poses or --pose-topic: a frame further than this many seconds "
                   "from every pose is an error row.")
@click.option("--smooth", type=Number(min=0), default=0.0, metavar="SECONDS",
              help="With --auto on a video: smooth the poses estimated frame by frame over a "
                   "window of this many seconds (a robust local fit that outvotes a wrong "
                   "frame; 0: each frame's own estimate).  [default: 0]")
@click.option("--steady", is_flag=True,
              help="A video's or bag's: frame every frame on the wall the first frame's default "
                   "frame shows, so that the wall stands still in the output (one focal "
                   "length), instead of each frame's own default frame.")
@click.option("--codec", type=click.Choice(VIDEO_CODEC_CHOICES), default="h264",
              show_default=True,
              help="A video's or bag's output: OUTDIR/NAME.mp4 (h264), OUTDIR/NAME.mkv "
                   "(ffv1, lossless), OUTDIR/NAME/000000.png... (png) or, for a bag, a bag "
                   "(OUTDIR/NAME.bag from ROS 1, else the ROS 2 MCAP bag OUTDIR/NAME) with "
                   "the topic NS/gsrwt/image and its camera_info; the input's timestamps "
                   "kept. The table is OUTDIR/NAME.csv, a row per frame.")
@click.option("--topic", default=None, metavar="TOPIC",
              help="INPUT is a ROS bag (.bag, .mcap, .db3 or a ROS 2 bag directory; needs "
                   "pip install 'gsrwt[ros]'): its image topic (sensor_msgs/Image or "
                   "CompressedImage), e.g. /camera/image_raw.")
@click.option("--pose-topic", default=None, metavar="TOPIC",
              help="A bag's poses: a PoseStamped, QuaternionStamped, Imu, JointState (with "
                   "--joints) or tf (with --wall-frame and --camera-frame) topic, "
                   "interpolated to each frame's stamp (slerp). Or --poses FILE.")
@click.option("--joints", default=None, metavar="PAN,TILT",
              help="With a JointState --pose-topic: the names of the pan and tilt joints "
                   "(radians; pan left and tilt up positive).")
@click.option("--joint-signs", default=None, metavar="S,S",
              help="With --joints: 1 or -1 for each joint, flipping a unit whose signs "
                   "differ [default: 1,1].")
@click.option("--wall-frame", default=None, metavar="FRAME",
              help="With a tf --pose-topic: the wall's frame (x right, y down, z into the "
                   "wall); with PoseStamped or QuaternionStamped, the header frame required.")
@click.option("--camera-frame", default=None, metavar="FRAME",
              help="With a tf --pose-topic: the camera's optical frame (x right, y down, z "
                   "forward).")
@click.option("--camera-info-topic", default=None, metavar="TOPIC",
              help="A bag's camera [default: camera_info in --topic's namespace]; --camera "
                   "replaces it, --focal, --cx, --cy override its values.")
def rectify(inputs: tuple[str, ...], outdir: Path | Location, recursive: bool,
            sidecar: Path | Location | None, **options: Any) -> None:
    """Rectify images into canonical frontal views of the wall they show (GS-RWT).

    INPUT is an image, a directory of images, or - to read paths from standard input.
    Parameters per image come from the first of: a row of --sidecar, a NAME.yaml beside
    the image, the --pan/--tilt/--focal options; with --auto, the pose of the rest is
    estimated from the image. Existing outputs made with the same options are skipped
    (rerun to resume), those made otherwise are errors (use --overwrite); every output is
    written whole or not at all. Exit code 1 if any image failed.

    \b
    Examples:
      gsrwt rectify sample_data/views --sidecar sample_data/views/views.csv -o rectified
      find sample_data/views -name '*.jpg' | gsrwt rectify - \\
          --sidecar sample_data/views/views.csv -o from-stdin
    """
    run = RunOptions.pop_from(options)
    poses, time_mode = options.pop("poses"), options.pop("time_mode")
    max_pose_gap, codec = options.pop("max_pose_gap"), options.pop("codec")
    steady, smooth = options.pop("steady"), options.pop("smooth")
    bag_options = BagOptions.pop_from(options)
    photo_frame = options["bbox"] is None  # an image whose pose its photo gives: its own
    options["bbox"] = options["bbox"] or "frontal"
    if bag_options.given() or any(is_bag_input(text) for text in inputs):
        from .bags import rectify_bag  # bags only when given

        _check_stream_options(inputs, sidecar, recursive, run, options, steady)
        _check_one_frame_size(options["bbox"], codec)
        settings, _ = settings_from_options(outdir, options)
        if settings.lens_from_lines:
            raise click.UsageError(f"{inputs[0]}: --lens-from-lines does not apply to a video "
                                   "or bag yet")
        table_path = options.pop("table_path")
        table = table_from_options(outdir, table_path, None)
        for name in ("auto", "min_confidence", "wall", "shard"):
            options.pop(name)
        rectify_bag(inputs, outdir, bag_options, poses, time_mode, max_pose_gap, codec,
                    settings, table, table_path is not None, run, view_defaults(options),
                    steady)
        return
    if poses is not None or any(is_video_name(text) for text in inputs if text != "-"):
        from .videos import check_video_request, rectify_video  # videos only when given

        check_video_request(inputs, poses, options["auto"], {
            "--sidecar": sidecar is not None, "-r": recursive, "--scheduler": bool(
                run.scheduler), "--shard": options["shard"] is not None,
            "--ext": options["ext"] is not None, "--dry-run": options["dry_run"]})
        if steady and options["bbox"] != "frontal":
            raise click.UsageError("--steady keeps the first frame's default frame: it "
                                   "needs --bbox frontal")
        _check_one_frame_size(options["bbox"], codec)
        if smooth and options["auto"] is None:
            raise click.UsageError("--smooth smooths poses estimated with --auto; a pose "
                                   "file's are used as they are")
        settings, _ = settings_from_options(outdir, options)
        if settings.lens_from_lines:
            raise click.UsageError(f"{inputs[0]}: --lens-from-lines does not apply to a video "
                                   "or bag yet")
        table_path = options.pop("table_path")
        table = table_from_options(outdir, table_path, None)
        auto, min_confidence, wall = (options.pop(name) for name in ("auto", "min_confidence",
                                                                      "wall"))
        options.pop("shard")
        estimating = (EstimateOptions(min_confidence, wall, settings.max_input_pixels,
                                      settings.orientation, auto, settings.lens_profile)
                      if auto is not None else None)
        rectify_video(inputs, outdir, poses, time_mode, max_pose_gap, codec, settings, table,
                      table_path is not None, run, view_defaults(options), steady,
                      estimating, smooth)
        return
    if smooth:
        raise click.UsageError("--smooth applies to a video with --auto only")
    if steady:
        raise click.UsageError("--steady applies to a video (with --poses) only")
    if codec == "bag":
        raise click.UsageError("--codec bag writes a bag's rectified topic: INPUT must be a "
                               "bag, with --topic")
    settings, extension = settings_from_options(outdir, options, photo_frame)
    table = table_from_options(outdir, options.pop("table_path"), options.pop("shard"))
    auto = options.pop("auto")
    estimating = (EstimateOptions(options.pop("min_confidence"), options.pop("wall"),
                                  settings.max_input_pixels, settings.orientation, auto,
                                  settings.lens_profile, settings.lens_from_lines)
                  if auto is not None else None)
    batch = plan_batch(inputs, outdir, recursive, sidecar, table, settings, extension,
                       estimating, view_kwargs=options)
    counts, stopped = run_planned(batch, settings, table, run)
    summary = f"{counts.ok} ok, {counts.skipped} skipped, {counts.failed} failed"
    if settings.dry_run:
        summary = f"{counts.planned} planned, {summary}"
    if stopped is not None:
        summary += f", {counts.interrupted} not done"
    end_batch(summary, "" if table.path == "-" else f"; table: {table.path}", stopped,
              counts.failed, run.quiet)


def _check_stream_options(inputs: tuple[str, ...], sidecar: Any, recursive: bool,
                          run: RunOptions, options: dict[str, Any], steady: bool) -> None:
    """Usage errors of options a bag does not take (as for a video)."""
    if options["auto"] is not None:
        raise click.UsageError(f"{inputs[0]}: --auto does not estimate a bag's poses; give "
                               "them with --pose-topic TOPIC or --poses FILE")
    for name, given in {"--sidecar": sidecar is not None, "-r": recursive,
                        "--scheduler": bool(run.scheduler),
                        "--shard": options["shard"] is not None,
                        "--ext": options["ext"] is not None,
                        "--dry-run": options["dry_run"]}.items():
        if given:
            raise click.UsageError(f"{name} does not apply to a bag (INPUT {inputs[0]})")
    if steady and options["bbox"] != "frontal":
        raise click.UsageError("--steady keeps the first frame's default frame: it "
                               "needs --bbox frontal")


def _check_one_frame_size(bbox: str, codec: str) -> None:
    """A usage error for a frame that gives every frame a size of its own (``full``,
    ``crop``, ``corners``: their pose's) written into a video file, which has one size."""
    if bbox in ("full", "crop", "corners") and codec in ("h264", "ffv1"):
        raise click.UsageError(f"--bbox {bbox} gives every frame a size of its own, and a "
                               f"{codec} video has one: use --codec png (an image sequence) "
                               "or the default frame (--steady holds it still)")


@dataclass(frozen=True)
class RunOptions:
    """How the batch runs: ``jobs`` processes (or a Dask ``scheduler`` with ``retries``),
    and whether it is ``quiet``; ``fork_workers``: the test suite's faster start-up."""

    jobs: int
    scheduler: str | None
    retries: int
    quiet: bool
    fork_workers: bool

    @classmethod
    def pop_from(cls, options: dict[str, Any]) -> RunOptions:
        root = click.get_current_context().find_root().obj
        return cls(options.pop("jobs") or os.cpu_count() or 1, options.pop("scheduler"),
                   options.pop("retries"), options.pop("quiet"),
                   getattr(root, "fork_workers", False))


def settings_from_options(outdir: Path | Location, options: dict[str, Any],
                          photo_frame: bool = False) -> tuple[Settings, str | None]:
    """The run's :class:`Settings` (framing, resampling, output format) and the output
    extension (``--ext``), from the options, which it takes out of ``options``; a bad value
    is a usage error naming its option. ``photo_frame``: ``--bbox`` was not given, so an
    image whose pose its photo gives is framed ``full`` (:attr:`Settings.from_photo`)."""
    bbox = parse_bbox(options.pop("bbox"))
    crop_aspect = parse_crop_aspect(options.pop("crop_aspect"), bbox)
    scale, px_per_unit = options.pop("scale"), options.pop("px_per_unit")
    max_stretch = options.pop("max_stretch")
    positive("--max-stretch", max_stretch)
    positive("--scale", scale)
    positive("--px-per-unit", px_per_unit)
    if scale is not None and px_per_unit is not None:
        raise click.UsageError("use either --scale or --px-per-unit, not both")
    max_size = options.pop("max_size")
    size_limit = parse_size(max_size) if max_size is not None else None
    alpha = options.pop("alpha")
    extension = options.pop("ext")
    if extension is not None:
        extension = canonical_extension(extension)
        try:
            check_writable(extension, "uint8", 4 if alpha else 3)
        except ImageFormatError as error:
            raise click.BadParameter(error.reason, param_hint="'--ext'") from None
    settings = Settings(
        framing=Framing(bbox=bbox, scale=scale or 1.0, px_per_unit=px_per_unit,
                        max_stretch=max_stretch,
                        max_pixels=parse_pixel_count(options.pop("max_pixels"), "--max-pixels"),
                        max_size=size_limit, margin=options.pop("margin"),
                        crop_aspect=crop_aspect,
                        max_area=(DEFAULT_MAX_AREA if scale is None and px_per_unit is None
                                  and size_limit is None else None)),
        interpolation=options.pop("interpolation"), fill=options.pop("fill"), alpha=alpha,
        quality=options.pop("quality"), overwrite=options.pop("overwrite"),
        dry_run=options.pop("dry_run"),
        max_input_pixels=parse_pixel_count(options.pop("max_input_pixels"),
                                           "--max-input-pixels"),
        root=outdir,
        describe=RectifyWording(bbox if isinstance(bbox, str) else "box",
                                px_per_unit is not None, size_limit is not None),
        antialias=options.pop("antialias"),
        orientation=options.pop("exif_orientation"),
        metadata=not options.pop("strip_metadata"),
        lens_profile=options.pop("lens_profile"),
        lens_from_lines=options.pop("lens_from_lines"),
    )
    check_lens_profile(settings.lens_profile)
    if photo_frame:
        settings = replace(settings, from_photo=replace(
            settings, framing=replace(settings.framing, bbox="full"),
            describe=replace(settings.describe, bbox="full")))
    return settings, extension


@dataclass(frozen=True)
class TableTarget:
    """Where the run's table goes: ``path`` (``-`` for stdout) in ``format``; ``default``:
    the output directory's own table, which says what made the outputs already there;
    ``shard``: ``(k, n)`` when this run is one of n slices."""

    path: str
    format: str
    default: str
    shard: tuple[int, int] | None


def table_from_options(outdir: Path | Location, table_path: str | None, shard: str | None
                       ) -> TableTarget:
    """``--table`` and ``--shard`` checked: a shard's table is named for its slice, a table
    file's name ends in a format's extension."""
    shard_k_n = None
    if shard is not None:
        try:
            shard_k_n = parse_shard(shard)
        except ValueError as error:
            raise click.BadParameter(str(error), param_hint="'--shard'") from None
    name = shard_table_name("gsrwt.csv", *shard_k_n) if shard_k_n else "gsrwt.csv"
    default = str(outdir / name)  # the record of the outputs in OUTDIR
    if table_path is None:
        return TableTarget(default, "csv", default, shard_k_n)
    table_format = "csv"
    if table_path != "-":
        table_format = format_from_extension(table_path) or ""
        if table_format not in ("csv", "tsv", "json", "jsonl"):
            raise click.BadParameter(
                "the table's name must end in .csv, .tsv, .json or .jsonl (or be -)",
                param_hint="'--table'",
            )
    return TableTarget(table_path, table_format, default, shard_k_n)


@dataclass
class PlannedBatch:
    """The jobs of this run (this shard's), the problems met listing the inputs, and the
    rows of the table this run replaces, by ``(image, output)``."""

    jobs: list[Job]
    unreadable: list[str]
    previous: dict[tuple[str, str], dict[str, Any]]


def plan_batch(inputs: tuple[str, ...], outdir: Path | Location, recursive: bool,
               sidecar: Path | Location | None, table: TableTarget, settings: Settings,
               extension: str | None, estimating: EstimateOptions | None,
               view_kwargs: dict[str, Any]) -> PlannedBatch:
    """Every check before any image is read: the inputs listed, the sidecar and --camera
    read, nothing the user gave us overwritten, the output directory and table writable;
    then the jobs planned (one shard's), and stale temporaries of a killed run removed."""
    if str(sidecar) == "-" and "-" in inputs:
        raise InputError("--sidecar - and INPUT - cannot both read standard input")
    loaded = load_sidecar_option(sidecar)
    sources, unreadable = collect_sources(inputs, recursive)
    if not sources and not unreadable:
        raise InputError(f"no images found in {' '.join(inputs)}")
    if isinstance(outdir, Location):  # a store is asked before its listing plans the jobs
        if not settings.dry_run:
            prepare_directory(outdir, f"-o {outdir}")
        try:
            outdir.exists()
        except OSError as error:
            raise InputError(f"-o {outdir}: cannot read ({error.strerror or error})") from None
    job_list = plan_jobs(sources, outdir, loaded, view_defaults(view_kwargs), extension,
                         estimating)
    if view_kwargs.get("camera"):
        try:  # a bad --camera file is a usage error, found before any image is read
            load_camera_file(str(view_kwargs["camera"]))
        except CalibrationError as error:
            raise InputError(str(error)) from None
    # A sidecar's camera files are read by the workers, each file once per worker: a file
    # that cannot be used is an error row of each image that names it (never the batch's).
    refuse_unsafe_outputs(
        inputs, sources, [job.output for job in job_list], outdir, recursive,
        None if table.path == "-" else location(table.path), sidecar,
    )
    if not settings.dry_run:
        prepare_directory(outdir, f"-o {outdir}")
    prepare_table(table.path, "--table")
    names = None
    if table.shard is not None:  # the whole list is planned and checked, one slice is run
        job_list = [job_list[index] for index in shard_slice(len(job_list), *table.shard)]
        # other shards may be writing beside ours, from other machines
        names = {job.output.name for job in job_list} | {location(table.path).name}
    for directory in sorted({job.output.parent for job in job_list} | {outdir}, key=str):
        if not isinstance(directory, Location):  # object stores have no temporaries
            remove_stale_temporaries(directory, names=names)
    # What made the outputs that exist: the table this run replaces (to stdout: OUTDIR's).
    previous = (previous_rows(table.path, table.format) if table.path != "-"
                else previous_rows(table.default, "csv"))
    return PlannedBatch(job_list, unreadable, previous)


def run_planned(batch: PlannedBatch, settings: Settings, table: TableTarget, run: RunOptions
                ) -> tuple[Counts, BaseException | None]:
    """Run the jobs (on local processes or the Dask scheduler) with a progress bar, writing
    the table row by row; returns the counts and the signal that stopped the run, if one did
    (every job then still has its row)."""
    progress = progress_bar(run.quiet, total=len(batch.jobs), unit="img")
    for problem in batch.unreadable:
        progress.write(f"Error: {one_line(problem)}", file=sys.stderr)
    counts = Counts(failed=len(batch.unreadable))
    stopped: BaseException | None = None
    try:
        with stop_on_signals(), contextlib.ExitStack() as cluster:
            executor = None
            if run.scheduler:
                executor = cluster.enter_context(
                    dask_executor(run.scheduler, run.jobs, run.retries, settings))
            on_row = cluster.enter_context(recorded_rows(
                table.path, RECTIFY_COLUMNS, table.format, counts,
                lambda line: progress.write(line, file=sys.stderr), lambda row: row["image"]))
            try:
                run_batch(batch.jobs, settings, run.jobs, on_row,
                          on_progress=lambda: progress.update(1), previous=batch.previous,
                          context=worker_context(run.fork_workers), executor=executor)
            except (KeyboardInterrupt, Terminated) as stop:
                stopped = stop  # every job has its row: the table is still written whole
    finally:
        progress.close()
    return counts, stopped
