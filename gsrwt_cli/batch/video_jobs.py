"""Streams (a video, a ROS bag's image topic): every frame rectified with the pose of its
moment, into a video, an image sequence or a bag.

The main process decodes (a :class:`~gsrwt_cli.batch.frame_sources.FrameSource`: a video
file or a bag's image topic), finds each frame's pose
(:class:`~gsrwt_cli.batch.frame_sources.FramePoses`: a pose log, or a bag's pose topic,
through a :class:`~gsrwt_cli.geometry.timeline.Timeline`) and encodes; the frames
are warped by the workers (:class:`FrameWorker`, the same plan and warp as a still image:
:func:`~gsrwt_cli.api.rectify.plan_image` and
:func:`~gsrwt_cli.imaging.images.warp_image`), at most
:data:`~gsrwt_cli.batch.executor.ITEMS_IN_FLIGHT` frames in flight per worker and a bounded
number waiting to be put back in order (:meth:`~gsrwt_cli.batch.executor.ProcessExecutor.
map_stream`). Every frame gets a row (:data:`~gsrwt_cli.tables.columns.VIDEO_COLUMNS`), in
order; a file cut short adds an error row after its last frame.

Outputs: ``h264`` and ``ffv1`` videos are encoded into a temporary file beside the output and
renamed when the whole video is done (:func:`~gsrwt_cli.io.outputs.open_atomic`), and a
``bag`` (the rectified image topic and the frontal camera's ``camera_info``,
:func:`~gsrwt_cli.inputs.bags.write_bag`) is written in a temporary directory beside it and
renamed, so a run that is stopped or killed leaves nothing under the output's name; ``png``
writes ``NAME/000000.png`` (six digits or more), each frame whole as it is done.

Reruns: a video output that exists and that the previous table records, frame by frame, as
made with these options (the ``made_with`` cell, the pose file's digest included) is
skipped whole (a bag likewise); one that exists otherwise is an error (``--overwrite``
redoes it). An image sequence continues: a frame whose file exists and is recorded so is
skipped (still decoded, not warped); one whose file exists without a record is made again
in memory and compared.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import queue
import secrets
import shutil
import threading
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..api.rectify import plan_image, view_for_image
from ..geometry.framing import steady_box
from ..geometry.pixelmap import PixelMap
from ..imaging.images import INTERPOLATIONS, Working, encode_image, warp_image, warp_working
from ..imaging.yuv import Yuv420, warp_yuv420
from ..inputs.records import RecordError, view_from_values
from ..io.outputs import (
    TEMPORARY_PATTERN,
    open_atomic,
    process_alive,
    remove_stale_temporaries,
    temporary_target,
    write_atomic,
)
from ..tables.rows import params_row, plan_row
from .executor import ProcessExecutor
from .frame_sources import (
    CachedTimeline,
    FramePoses,
    FrameSource,
    SourceEndedError,
    StreamFrame,
)
from .in_order import row_in_hand
from .job_errors import JobError, error_text
from .rectify_jobs import NOT_MADE_SO, Counts
from .settings import Settings
from .workers import ProcessWorker

#: ``--codec``: the video codecs (:data:`~gsrwt_cli.imaging.videos.VIDEO_CODECS`), ``png``,
#: an image sequence, and ``bag``, a ROS bag (a bag's input only).
CODEC_CHOICES = ("h264", "ffv1", "png", "bag")
#: ``--time``: the pose file's ``time`` counts from the first frame, or on the container's
#: own clock (``pts * time_base``).
TIME_MODES = ("relative", "absolute")
#: ``--max-pose-gap``'s default, in seconds.
DEFAULT_MAX_POSE_GAP = 0.5
#: Digits of an image sequence's frame numbers (more when there are more frames).
FRAME_DIGITS = 6

Row = dict[str, Any]


@dataclass(frozen=True)
class StreamJob:
    """One stream to rectify: its file (a video, a bag: the table's ``image``), how to open
    its frames (``open_source``), the output (a video or bag, or the directory of an image
    sequence), the codec, its poses (with the view options and the bag's camera), and what
    makes its output (``made_with``); ``topic``: a bag output's image topic."""

    source: Path
    output: Path
    codec: str
    poses: FramePoses
    open_source: Callable[[], FrameSource]
    made_with: str = ""
    #: ``--steady``: every frame framed on the wall the first frame's default frame shows.
    steady: bool = False
    topic: str | None = None


@dataclass(frozen=True)
class FrameJob:
    """One frame for a worker: its ``index``, ``time``, pixels and view values (None with an
    ``error`` known before the warp), where its values came from, its ``output`` (an image
    sequence's file; None: the pixels come back for the encoder), whether that file existed
    and the previous table's ``record`` of it."""

    image: str
    index: int
    time: float | None
    pixels: np.ndarray | None
    values: Mapping[str, Any] | None
    where: str
    output: Path | None
    shown_output: str
    focal_source: str = "option"
    error: str | None = None
    existed: bool = False
    record: Mapping[str, Any] | None = None
    #: ``--steady``: the view values of the video's first frame, whose frame every frame keeps.
    steady_from: Mapping[str, Any] | None = None
    #: A bag output: the output's camera matrix comes back with the pixels (``_camera``).
    camera: bool = False
    pose_source: str = "poses"
    #: ``rectify VIDEO --auto``: the confidence of the frame's own estimate (None: its pose
    #: was interpolated between those of other frames, or not estimated).
    confidence: float | None = None


def output_of(source: Path, outdir: Path, codec: str) -> Path:
    """Where a stream's output goes: ``OUTDIR/NAME.mp4`` (h264), ``OUTDIR/NAME.mkv``
    (ffv1), the directory ``OUTDIR/NAME`` (png), or for a bag ``OUTDIR/NAME.bag`` (a ROS 1
    input) or the ROS 2 bag directory ``OUTDIR/NAME`` (MCAP)."""
    stem = outdir / (source.stem if source.suffix else source.name)
    if codec == "png":
        return stem
    if codec == "bag":
        return stem.with_suffix(".bag") if source.suffix == ".bag" else stem
    from ..imaging.videos import VIDEO_CODECS

    return stem.with_suffix(VIDEO_CODECS[codec].extension)


def takes_planes(codec: str, settings: Settings) -> bool:
    """Whether a video's frames are decoded as their YUV 4:2:0 planes for this output
    (:mod:`~gsrwt_cli.imaging.yuv`): a ``yuv420p`` video codec (``h264``) without alpha;
    each frame whose camera has a lens is still warped in BGR (:func:`process_frame`)."""
    from ..imaging.videos import VIDEO_CODECS

    codec_of = VIDEO_CODECS.get(codec)
    return codec_of is not None and codec_of.pixel_format == "yuv420p" and not settings.alpha


def frame_file(directory: Path, index: int) -> Path:
    """An image sequence's file of frame ``index``: ``000042.png``."""
    return directory / f"{index:0{FRAME_DIGITS}d}.png"


def process_frame(job: FrameJob, settings: Settings, made_with: str) -> Row:
    """Rectify one frame and return its row (with ``_pixels``, the warped frame, when it
    goes to the encoder, and ``_camera``, its camera matrix, for a bag); never raises for a
    bad frame."""
    row: Row = {"image": job.image, "frame": job.index, "time": job.time,
                "output": job.shown_output}
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if job.error is not None:
                raise JobError(job.error)
            if job.record is not None:
                return {**job.record, "status": "skipped", "error": None}
            assert job.values is not None and job.pixels is not None
            try:
                view = view_from_values(job.values, job.where)
            except RecordError as error:
                raise JobError(str(error)) from None
            row.update(params_row(view, job.image), focal_source=job.focal_source,
                       pose_source=job.pose_source, confidence=job.confidence)
            height, width = job.pixels.shape[:2]
            framing = settings.framing
            if job.steady_from is not None:
                first = view_for_image(view_from_values(job.steady_from, job.where), width,
                                       height)
                framing = replace(framing, bbox=steady_box(view_for_image(view, width, height),
                                                           first))
            plan = plan_image(view, width, height, framing)
            pixels = job.pixels
            if isinstance(pixels, Yuv420):
                if _warps_planes(job, plan.pixel_map, settings):
                    row.update(plan_row(plan), image=job.image, made_with=made_with,
                               status="ok", _pixels=warp_yuv420(
                                   pixels, plan.pixel_map, INTERPOLATIONS[settings.interpolation],
                                   settings.fill, settings.antialias))
                    return row
                pixels = pixels.to_bgr()  # as the decoder's frame would have been converted
            if settings.alpha:
                warped = warp_image(pixels, plan.pixel_map, settings.interpolation,
                                    settings.fill, True, settings.antialias)
            else:  # as decoded: at a frame's size, padding BGR to BGRA and back costs more
                # than the faster BGRA warp saves (640x480: 4.4 ms against 1.6, measured)
                warped = warp_working(Working(pixels), plan.pixel_map,
                                      settings.interpolation, settings.fill, False,
                                      antialias=settings.antialias).pixels
            status = "ok"
            if job.output is not None:
                encoded = encode_image(warped, ".png")
                checking = job.existed and not settings.overwrite and os.path.lexists(
                    job.output)
                if checking:
                    with open(job.output, "rb") as handle:
                        if handle.read(len(encoded) + 1) != encoded:
                            raise JobError(NOT_MADE_SO)
                    status = "skipped"
                else:
                    write_atomic(job.output, encoded, root=settings.root)
            else:
                row["_pixels"] = warped
                if job.camera:
                    row["_camera"] = plan.output_camera()[0]
        row.update(plan_row(plan), image=job.image, made_with=made_with, status=status)
    except Exception as error:  # every failure of one frame is that frame's row
        row.update(status="error", error=error_text(error, settings.describe))
    return row


def _warps_planes(job: FrameJob, pixel_map: PixelMap, settings: Settings) -> bool:
    """Whether a frame decoded as YUV 4:2:0 planes is warped as them (for the H.264 encoder,
    :mod:`~gsrwt_cli.imaging.yuv`): through a pinhole (a lens's map is warped in BGR),
    without alpha, for a video (an image sequence and a bag take BGR), at an even size."""
    width, height = pixel_map.size
    return (pixel_map.lens is None and pixel_map.output_lens is None and not settings.alpha
            and job.output is None and not job.camera and width % 2 == 0 and height % 2 == 0)


class FrameWorker(ProcessWorker):
    """One stream worker: the settings and the ``made_with`` of the stream's output."""

    def __init__(self, settings: Settings, made_with: str, opencv_threads: int = 0) -> None:
        super().__init__(opencv_threads)
        self.settings = settings
        self.made_with = made_with

    def __call__(self, job: FrameJob) -> Row:
        return process_frame(job, self.settings, self.made_with)


class InProcess:
    """``-j 1``: the frames warped in this process, one at a time (the executor's
    :meth:`~gsrwt_cli.batch.executor.ProcessExecutor.map_stream` shape)."""

    def __init__(self, worker: Callable[[FrameJob], Row]) -> None:
        self.worker = worker

    def map_stream(self, items: Iterator[FrameJob]) -> Iterator[tuple[int, Row]]:
        for index, item in enumerate(items):
            yield index, self.worker(item)


def _dead_frame_row(job: FrameJob, reason: str) -> Row:
    return {"image": job.image, "frame": job.index, "time": job.time,
            "output": job.shown_output, "status": "error", "error": reason}


def _remove_temporaries_of(job: FrameJob, pid: int) -> None:
    if job.output is not None:
        remove_stale_temporaries(job.output.parent, {pid})


@dataclass
class _Decoding:
    """What the decoding loop learnt: the frame count, why it stopped early, each frame's
    output timestamps (``pts`` for a video, ``stamp_ns`` for a bag)."""

    frames: int = 0
    end_error: str | None = None
    pts: dict[int, int | None] = field(default_factory=dict)
    stamps: dict[int, int | None] = field(default_factory=dict)
    steady_from: Mapping[str, Any] | None = None  # --steady: the first frame's values


def run_stream(job: StreamJob, settings: Settings, processes: int,
               on_row: Callable[[Row], None], *,
               on_progress: Callable[[], None] | None = None,
               previous: Sequence[Mapping[str, Any]] = (),
               context: multiprocessing.context.BaseContext | None = None) -> Counts:
    """Rectify every frame of ``job``'s stream and hand each row to ``on_row``, in frame
    order; returns the counts. ``previous``: the last table's rows of this stream.

    A stop (``KeyboardInterrupt``, SIGTERM's exception) ends the workers and goes on after
    the rows of the frames decoded so far: ``interrupted``, every one of them for a video
    or bag (whose file is then not written), those not done for an image sequence.
    """
    from ..inputs.bags import BagError
    from ..inputs.videos import VideoError

    counts = Counts()

    def deliver(row: Row) -> None:
        row.pop("_pixels", None)
        row.pop("_camera", None)
        counts.add(row)
        on_row(row)

    image = str(job.source)
    shown = str(job.output)
    if job.codec != "png" and not settings.overwrite and os.path.lexists(job.output):
        for row in _rows_of_finished_video(job, previous, shown):
            deliver(row)
        return counts
    try:
        source = job.open_source()
    except (VideoError, BagError) as error:
        deliver({"image": image, "output": shown, "status": "error", "error": str(error)})
        return counts
    try:
        poses = CachedTimeline(job.poses)  # an estimated video's first pass, stoppable
        if job.codec == "png":
            _run(job, settings, processes, source, poses, deliver, on_progress, previous,
                 context, None)
        else:
            _run_encoded(job, settings, processes, source, poses, deliver, on_progress,
                         context)
    finally:
        source.close()
    return counts


def _rows_of_finished_video(job: StreamJob, previous: Sequence[Mapping[str, Any]],
                            shown: str) -> list[Row]:
    """The rows of a video or bag output that exists: the previous table's, ``skipped``,
    when they record it whole as made with these options; else one error row."""
    rows = [dict(row) for row in previous if row.get("output") == shown]
    complete = bool(rows) and all(
        row.get("made_with") in (None, "", job.made_with) and row.get("status") in (
            "ok", "skipped", "error") for row in rows) and any(
        row.get("made_with") == job.made_with for row in rows)
    if not complete:
        error = (NOT_MADE_SO if not rows or all(row.get("made_with") in (None, "", job.made_with)
                                                for row in rows) else
                 "its output exists from a run with other options (the previous table's "
                 "made_with differs); use --overwrite to redo it")
        return [{"image": str(job.source), "output": shown, "status": "error", "error": error}]
    for row in rows:
        if row.get("status") == "ok":
            row["status"] = "skipped"
    return rows


class _NothingWrittenError(Exception):
    """No frame reached the encoder: no file is made."""


def _run_encoded(job: StreamJob, settings: Settings, processes: int, source: FrameSource,
                 poses: FramePoses, deliver: Callable[[Row], None],
                 on_progress: Callable[[], None] | None,
                 context: multiprocessing.context.BaseContext | None) -> None:
    """A video or bag output: rows held until the file is whole (a stopped run's are
    ``interrupted``: its file is not written)."""
    from ..imaging.videos import VideoEncodeError

    held: list[Row] = []
    try:
        with _output_sink(job, settings, source) as encoder:
            decoding = _Decoding()
            writer = _EncoderThread(encoder, (VideoEncodeError, ValueError))

            def encode(row: Row) -> None:
                pixels = row.pop("_pixels", None)
                camera = row.pop("_camera", None)
                pts = decoding.pts.pop(row.get("frame"), None)
                stamp = decoding.stamps.pop(row.get("frame"), None)
                if pixels is not None and row["status"] == "ok":
                    key: Any = (stamp, camera) if job.codec == "bag" else (
                        pts if pts is not None else row["frame"])
                    writer.put(row, pixels, key)
                held.append(row)

            try:
                _run(job, settings, processes, source, poses, encode, on_progress, (),
                     context, decoding)
                writer.finish()
                if encoder.frames == 0:
                    raise _NothingWrittenError
                encoder.close()
            except BaseException:
                writer.finish(drop=True)
                encoder.abandon()
                raise
    except _NothingWrittenError:  # every frame failed: their rows, and no file
        pass
    except BaseException as stop:
        failed = isinstance(stop, Exception)
        for row in held:
            if row["status"] == "ok" and failed:
                row.update(status="error",
                           error=f"the output could not be written: {error_text(stop)}")
            elif row["status"] == "ok":
                row.update(status="interrupted", error="not done: the run was interrupted")
            deliver(row)
        if not failed:
            raise
        return
    for row in held:
        deliver(row)


@contextlib.contextmanager
def _output_sink(job: StreamJob, settings: Settings, source: FrameSource) -> Iterator[Any]:
    """The encoder of a video output (into :func:`open_atomic`'s temporary file) or the
    writer of a bag output (:class:`BagSink`)."""
    if job.codec == "bag":
        assert job.topic is not None
        yield BagSink(job.output, job.topic, settings)
        return
    from ..imaging.videos import VIDEO_CODECS, VideoEncoder

    with open_atomic(job.output, "wb", root=settings.root) as handle:
        yield VideoEncoder(handle, VIDEO_CODECS[job.codec], source.time_base, source.rate)


class BagSink:
    """A bag output written by :func:`~gsrwt_cli.inputs.bags.write_bag` in a thread of its
    own, frame by frame as :meth:`write` hands them over: into a temporary directory beside
    the output (``.NAME.gsrwt-PID-XXXX.part``), renamed to the output's name by
    :meth:`close` (an existing output, with ``--overwrite``, is moved aside first and then
    removed), removed by :meth:`abandon`."""

    _END, _ABORT = object(), object()

    def __init__(self, output: Path, topic: str, settings: Settings) -> None:
        from ..io.outputs import check_inside

        if settings.root is not None:
            check_inside(settings.root, output)
        self.output, self.topic = output, topic
        self.temporary = output.parent / (f".{output.name}.gsrwt-{os.getpid()}-"
                                          f"{secrets.token_hex(4)}.part")
        self.temporary.mkdir()
        self.items: queue.Queue[Any] = queue.Queue(2)
        self.frames = 0
        self.failure: BaseException | None = None
        self.thread = threading.Thread(target=self._write, daemon=True)
        self.thread.start()

    def _items(self) -> Iterator[tuple[int, np.ndarray, np.ndarray]]:
        while True:
            item = self.items.get()
            if item is self._END:
                return
            if item is self._ABORT:
                raise _NothingWrittenError
            yield item

    def _write(self) -> None:
        from ..inputs.bags import write_bag

        try:
            write_bag(self.temporary / self.output.name, self.topic, self._items(), None)
        except BaseException as error:  # reported by close
            self.failure = error
            while self.items.get() not in (self._END, self._ABORT):
                pass

    def write(self, pixels: np.ndarray, key: tuple[int | None, np.ndarray | None]) -> None:
        """Queue one frame: ``key`` is its stamp (nanoseconds) and camera matrix."""
        stamp, camera = key
        if self.failure is not None:
            raise self.failure
        if stamp is None or camera is None:
            raise ValueError("the frame has no stamp or camera")
        self.items.put((int(stamp), pixels, camera))
        self.frames += 1

    def close(self) -> None:
        """Finish the bag and put it under the output's name."""
        self.items.put(self._END)
        self.thread.join()
        try:
            if self.failure is not None:
                raise self.failure
            made = self.temporary / self.output.name
            if os.path.lexists(self.output):  # --overwrite: the old one moved aside first
                aside = self.output.parent / (f".{self.output.name}.gsrwt-{os.getpid()}-"
                                              f"{secrets.token_hex(4)}.part")
                os.rename(self.output, aside)
                os.rename(made, self.output)
                _remove_tree(aside)
            else:
                os.rename(made, self.output)
        finally:
            _remove_tree(self.temporary)

    def abandon(self) -> None:
        """Drop the bag being written."""
        if self.thread.is_alive():
            self.items.put(self._ABORT)
            self.thread.join()
        _remove_tree(self.temporary)


def _remove_tree(path: Path) -> None:
    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            path.unlink()


#: Frames waiting for the encoder's thread (each a warped frame in memory).
ENCODE_AHEAD = 4


class _EncoderThread:
    """The encoder in a thread of its own (PyAV lets go of the GIL while FFmpeg encodes), so
    that decoding and the workers' results go on while a frame is encoded; at most
    :data:`ENCODE_AHEAD` frames wait. A frame the encoder refuses (one of ``refused``) makes
    its row an ``error``."""

    def __init__(self, encoder: Any, refused: tuple[type[BaseException], ...]) -> None:
        self.encoder = encoder
        self.refused = refused
        self.frames: queue.Queue[tuple[Row, np.ndarray, Any] | None] = queue.Queue(
            ENCODE_AHEAD)
        self.failure: BaseException | None = None
        self.drop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            item = self.frames.get()
            if item is None:
                return
            row, pixels, key = item
            if self.drop or self.failure is not None:
                continue
            try:
                self.encoder.write(pixels, key)
            except self.refused as error:
                row.update(status="error", error=error_text(error))
            except Exception as error:  # the file cannot be finished: reported by finish
                self.failure = error

    def put(self, row: Row, pixels: np.ndarray, key: Any) -> None:
        if self.failure is not None:
            raise self.failure
        self.frames.put((row, pixels, key))

    def finish(self, drop: bool = False) -> None:
        """Wait for the frames queued (``drop``: throw them away) and end the thread;
        raises what stopped the encoder, if anything did."""
        self.drop = self.drop or drop
        self.frames.put(None)
        self.thread.join()
        if self.failure is not None and not drop:
            raise self.failure


def _run(job: StreamJob, settings: Settings, processes: int, source: FrameSource,
         poses: FramePoses, deliver: Callable[[Row], None],
         on_progress: Callable[[], None] | None, previous: Sequence[Mapping[str, Any]],
         context: multiprocessing.context.BaseContext | None,
         decoding: _Decoding | None) -> None:
    """Decode, warp on the executor, and hand the rows over in frame order."""
    decoding = decoding or _Decoding()
    image, png = str(job.source), job.codec == "png"
    recorded = {str(row.get("output")): row for row in previous
                if row.get("status") in ("ok", "skipped") and not row.get("error")}
    jobs_out: dict[int, FrameJob] = {}

    def frame_jobs() -> Iterator[FrameJob]:
        frames = source.frames()
        while True:
            try:
                item = next(frames)
            except StopIteration:
                return
            except SourceEndedError as error:
                decoding.end_error = str(error)
                return
            decoding.frames = item.index + 1
            decoding.pts[item.index] = item.pts
            decoding.stamps[item.index] = item.stamp_ns
            made = _frame_job(job, item, poses, png, recorded, settings, image)
            if job.steady and made.error is None and made.values is not None:
                if decoding.steady_from is None:
                    decoding.steady_from = made.values
                made = replace(made, steady_from=decoding.steady_from)
            jobs_out[item.index] = replace(made, pixels=None)
            yield made

    if processes > 1:
        executor: Any = ProcessExecutor(
            FrameWorker.in_own_process, (settings, job.made_with, 1),
            processes, on_death=_dead_frame_row, on_abandon=_remove_temporaries_of,
            context=context or multiprocessing.get_context())
    else:
        executor = InProcess(FrameWorker(settings, job.made_with))
    waiting: dict[int, Row] = {}
    following = 0
    results = executor.map_stream(frame_jobs())
    try:
        for index, row in results:
            waiting[index] = row
            while following in waiting:
                jobs_out.pop(following, None)
                if on_progress is not None:
                    on_progress()
                with row_in_hand():
                    deliver(waiting.pop(following))
                    following += 1
    except BaseException:
        results.close()
        for index in sorted(set(jobs_out) | set(waiting)):
            if index < following:
                continue
            row = waiting.pop(index, None)
            if row is None or (not png):
                frame = jobs_out[index]
                row = _dead_frame_row(frame, "not done: the run was interrupted")
                row["status"] = "interrupted"
            deliver(row)
        raise
    finally:
        results.close()
    if decoding.end_error is not None:
        deliver({"image": image, "frame": decoding.frames, "output": str(job.output),
                 "status": "error", "error": decoding.end_error})


def _frame_job(job: StreamJob, item: StreamFrame, poses: FramePoses, png: bool,
               recorded: Mapping[str, Mapping[str, Any]], settings: Settings,
               image: str) -> FrameJob:
    """The frame's job: its view values from its poses, or the error it already has."""
    output = frame_file(job.output, item.index) if png else None
    shown = str(output) if output is not None else str(job.output)
    base = FrameJob(image, item.index, item.time, None, None, "", output, shown,
                    camera=job.codec == "bag", pose_source=poses.pose_source)
    if item.pixels is None:
        return replace(base, error=item.error or f"frame {item.index} has no image")
    try:
        values, where, focal_source = poses.values_at(item)
    except JobError as error:
        return replace(base, error=str(error))
    existed = output is not None and os.path.lexists(output)
    record = None
    if existed and not settings.overwrite:
        previous = recorded.get(shown)
        if previous is not None and previous.get("made_with") == job.made_with:
            record = previous
        elif previous is not None:
            return replace(base, values=values, where=where,
                           error="its output exists from a run with other options (the "
                                 "previous table's made_with differs); use --overwrite to "
                                 "redo it")
    confidence = getattr(poses, "confidence", {}).get(item.index)  # an estimated video's
    return replace(base, pixels=None if record else item.pixels, values=values, where=where,
                   focal_source=focal_source, existed=existed, record=record,
                   confidence=confidence)


def remove_video_temporaries(job: StreamJob) -> None:
    """Remove what a killed run left half-written for this stream (its temporary file or
    bag directory, or those of its image sequence's frames)."""
    with contextlib.suppress(OSError):
        remove_stale_temporaries(job.output.parent, names={job.output.name})
        if job.codec == "bag":
            _remove_stale_directories(job.output.parent, job.output.name)
        if job.codec == "png" and job.output.is_dir():
            remove_stale_temporaries(job.output)


def _remove_stale_directories(directory: Path, name: str) -> None:
    """Temporary directories of ours for ``name`` (a bag being written) whose process is
    gone."""
    for entry in os.scandir(directory):
        match = TEMPORARY_PATTERN.match(entry.name)
        if match is None or temporary_target(entry.name) != name:
            continue
        if not entry.is_dir(follow_symlinks=False) or process_alive(int(match.group(1))):
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
