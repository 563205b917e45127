"""Pose estimates of image files: the camera of each, the estimate, its sidecar row, its
picture; and the batch of them on the executor's worker processes (``gsrwt estimate``,
``gsrwt rectify --auto``).

A row is a sidecar row (``image, pan, tilt, roll, focal, cx, cy, width, height``, the
columns ``gsrwt rectify --sidecar`` reads) followed by what the estimate says of itself.
"""

from __future__ import annotations

import math
import multiprocessing
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..api.estimate import (
    DEFAULT_MIN_CONFIDENCE,
    DIRECTION_NAMES,
    EXIF_FOCAL_SPREAD,
    WALL_CHOICES,
    EstimateError,
    PoseEstimate,
    estimate_pose,
    remedy,
)
from ..base.messages import shown_below
from ..geometry.camera import Intrinsics
from ..geometry.guides import GuideError
from ..geometry.orientation import displayed_size
from ..imaging.images import (
    DEFAULT_MAX_INPUT_PIXELS,
    encode_image,
    file_orientation,
    image_file_size,
    read_image,
)
from ..inputs.focal import exif_head, with_focal
from ..inputs.guides import fit_pose, guided_pose, has_guides
from ..inputs.lensfun import lens_source_of, needs_exif, with_lens_profile
from ..inputs.records import (
    GSRWT_FIELDS,
    POSE_FIELDS,
    SENSOR_FIELDS,
    RecordError,
    guided_view_values,
    view_from_values,
)
from ..io.outputs import write_atomic
from ..tables.columns import ESTIMATE_COLUMNS  # noqa: F401  (named here too)
from .executor import ProcessExecutor
from .in_order import run_in_order
from .job_errors import error_text
from .workers import ProcessWorker

#: How ``--auto`` finds a pose: from the image's lines, or from a document's corners.
AUTO_MODES = ("lines", "document")
#: A refusal for low confidence names the vertical's uncertainty when it is surely up with
#: less than this probability (:func:`~gsrwt_cli.api.estimate.upright_probability`).
UPRIGHT_NOTED = 0.95
#: With the focal length known, four corners over-determine a rectangle's pose by one
#: number: the root mean square (pixels) by which the best rectangle's corners may miss the
#: found ones. What 0.5 px of error on each corner coordinate explains at 99 % (chi-square, one
#: degree of freedom: rms <= 0.5 * sqrt(6.63 / 8) = 0.46); found corners are within 0.15 px
#: (median) on rendered pages.
MAX_DOCUMENT_RMS_PX = 0.46

#: Fields of a record that give a pose: an estimate ignores them (it makes its own).
_POSE_VALUES = ("pan", "tilt", "roll", *GSRWT_FIELDS, *POSE_FIELDS)


@dataclass(frozen=True)
class EstimateOptions:
    """How poses are estimated: results below ``min_confidence`` are errors; ``wall`` is
    ``frontal`` (``|pan| <= 45``) or ``dominant`` (:func:`~gsrwt_cli.api.estimate.
    world_from_camera_of`)."""

    min_confidence: float = DEFAULT_MIN_CONFIDENCE
    wall: str = "frontal"
    max_input_pixels: float = DEFAULT_MAX_INPUT_PIXELS
    #: ``exif``: the photo as its EXIF orientation displays it; ``ignore``: the stored pixels.
    orientation: str = "exif"
    #: ``lines``: the pose from the image's lines; ``document``: from the corners of the
    #: largest clear quadrilateral of strong edges (:mod:`~gsrwt_cli.vision.document`).
    mode: str = "lines"
    #: ``--lens-profile``: ``auto``, ``lensfun`` or ``off`` (:mod:`~gsrwt_cli.inputs.lensfun`).
    lens_profile: str = "auto"
    #: ``--lens-from-lines``: k1 from the image's lines where no lens is given nor profiled
    #: (:mod:`~gsrwt_cli.api.lens_lines`).
    lens_from_lines: bool = False

    def __post_init__(self) -> None:
        if self.wall not in WALL_CHOICES:
            raise ValueError(f"wall must be one of {', '.join(WALL_CHOICES)}")
        if self.mode not in AUTO_MODES:
            raise ValueError(f"mode must be one of {', '.join(AUTO_MODES)}")


def camera_for(path: Path, values: Mapping[str, Any], where: str, orientation: int = 1,
               lens_profile: str = "auto"
               ) -> tuple[Intrinsics | None, str, tuple[float, float] | None, dict[str, Any]]:
    """The intrinsics an image's values give (their pose left out), where its focal length
    comes from (``option``, ``sidecar``, ``camera``, ``exif``, or ``estimated`` when nothing
    gives one: then the intrinsics are None), the principal point given without a focal
    length, and the lens's ``lens_source`` and ``lens_profile`` (a lensfun profile when the
    values give no lens and the focal length is known: :mod:`~gsrwt_cli.inputs.lensfun`); all
    of the photo as its EXIF ``orientation`` displays it (1: as stored); ``lens_profile``:
    ``--lens-profile``'s mode. Raises
    :class:`~gsrwt_cli.inputs.records.RecordError` for a bad value."""
    own = {name: value for name, value in values.items() if name not in _POSE_VALUES}
    head = exif_head(path) if needs_exif(own, lens_profile) else None  # one read: focal, lens
    own, source = with_focal(path, own, where, orientation, head)
    if source is None:
        view = view_from_values({**own, "pan": 0, "tilt": 0, "focal": 1.0}, where, orientation)
        given = own.get("cx") not in (None, "")
        lens = {"lens_source": lens_source_of(own) or "none", "lens_profile": None}
        return None, "estimated", (view.cx, view.cy) if given else None, lens
    own, lens_source, lens_profile = with_lens_profile(
        head, image_file_size(path) if head is not None else None, own, lens_profile)
    return (view_from_values({**own, "pan": 0, "tilt": 0}, where, orientation).intrinsics,
            source, None, {"lens_source": lens_source, "lens_profile": lens_profile})


def orientation_of(path: Path, options: EstimateOptions) -> int:
    """The EXIF orientation an image is estimated in (1 with ``orientation="ignore"``)."""
    return 1 if options.orientation == "ignore" else file_orientation(path)


def lens_unknown(camera: Intrinsics | None, source: str, values: Mapping[str, Any]) -> bool:
    """Whether an estimate is checked for a lens nobody calibrated
    (:func:`~gsrwt_cli.api.lens_lines.checked_for_a_lens`): with no camera at all, or with
    square pixels and no lens (from a calibration file, a sidecar's coefficients or lensfun)
    and a focal length from EXIF or given alone (``--focal``, a sidecar's ``focal``, with no
    principal point in ``values``). A principal point comes from a calibration, which
    measures the lens too: a camera given with one, or by a calibration file, is taken as
    the pinhole it says. A focal length alone (a datasheet's, a field of view's) says
    nothing of the lens, no more than EXIF's does."""
    if camera is None:
        return True
    if camera.lens is not None or camera.fx != camera.fy or camera.skew != 0:
        return False
    return source == "exif" or (source in ("option", "sidecar") and all(
        values.get(name) in (None, "") for name in ("cx", "cy")))


def estimate_as_given(image: np.ndarray, camera: Intrinsics | None, source: str,
                      values: Mapping[str, Any], principal_point: tuple[float, float] | None,
                      options: EstimateOptions) -> PoseEstimate:
    """The pose of ``image`` from its lines as ``gsrwt estimate`` makes it of a photo or a
    video's frame, given ``camera`` (None: none at all) from ``source`` with the user's
    ``values``: an EXIF focal length, a few per cent off, refined by the segments where
    they pin it (:data:`~gsrwt_cli.api.estimate.EXIF_FOCAL_SPREAD`); the estimate checked
    for a lens nobody calibrated (:func:`lens_unknown`), whose bent edges mislead."""
    spread = EXIF_FOCAL_SPREAD if source == "exif" and camera is not None else 0.0
    estimate = estimate_pose(image, camera, principal_point=principal_point, wall=options.wall,
                             focal_spread=spread)
    if lens_unknown(camera, source, values):
        from ..api.lens_lines import checked_for_a_lens

        estimate = checked_for_a_lens(image, estimate, principal_point, options.min_confidence,
                                      camera=camera)
    return estimate


def estimate_file(path: Path, values: Mapping[str, Any], where: str, options: EstimateOptions
                  ) -> tuple[PoseEstimate, Intrinsics | None, str, np.ndarray, dict[str, Any]]:
    """Read ``path`` and estimate its pose: the estimate, the camera it was given (None when
    the focal length was estimated; with ``--lens-from-lines``'s lens when taken; with the
    focal length the segments refined, source ``exif+lines``, when it came from EXIF and the
    camera has no lens: :data:`~gsrwt_cli.api.estimate.EXIF_FOCAL_SPREAD`), the focal
    length's source, the decoded image and the lens's columns (:func:`camera_for`; with
    ``--lens-from-lines`` where no lens is given, ``lens_source`` ``lines`` when the lens is
    taken, and ``lines``: the :class:`~gsrwt_cli.api.lens_lines.LinesLens` found)."""
    orientation = orientation_of(path, options)
    camera, source, principal_point, lens = camera_for(path, values, where, orientation,
                                                       options.lens_profile)
    image = read_image(path, options.max_input_pixels, orientation)
    height, width = image.shape[:2]
    if camera is not None and camera.width is not None and (
            (camera.width, camera.height) != (width, height)):
        raise ValueError(f"the parameters say {camera.width}x{camera.height} pixels but the "
                         f"image is {width}x{height}")
    if options.lens_from_lines and lens["lens_source"] == "none":
        from ..api.lens_lines import (  # only when asked for
            checked_for_a_lens,
            estimate_with_lens_from_lines,
        )

        estimate, found = estimate_with_lens_from_lines(
            image, camera, principal_point=principal_point, wall=options.wall)
        if lens_unknown(camera, source, values) and not found.taken:  # as without it
            estimate = checked_for_a_lens(image, estimate, principal_point,
                                          options.min_confidence, found, camera)
        lens = {**lens, "lines": found}
        if found.taken:
            lens["lens_source"] = "lines"
            if camera is not None:
                camera = Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew,
                                    camera.width, camera.height, found.lens())
        return estimate, camera, source, image, lens
    estimate = estimate_as_given(image, camera, source, values, principal_point, options)
    if source == "exif" and camera is not None and estimate.focal_estimated and estimate.focal:
        camera = Intrinsics(estimate.focal, estimate.focal, camera.cx, camera.cy, camera.skew,
                            camera.width, camera.height, camera.lens)
        source = "exif+lines"
    return estimate, camera, source, image, lens


def lens_columns(lens: Mapping[str, Any], camera: Intrinsics | None) -> dict[str, Any]:
    """``gsrwt estimate --lens-from-lines``'s lens columns: ``lens_source``, the lens taken
    (``distortion_model``, ``k1``: what ``rectify --sidecar`` reads back) and ``lens_lines``,
    the evidence or why it was refused. ``camera``: the estimate's camera (a given lens's
    coefficients are the sidecar's or the calibration file's: not repeated)."""
    found = lens.get("lines")
    row: dict[str, Any] = {"lens_source": lens["lens_source"]}
    if found is not None:
        row["lens_lines"] = found.summary()
        if found.taken:
            row.update(distortion_model="plumb_bob", k1=round(found.k1, 6))
    elif lens["lens_source"] == "lensfun" and camera is not None and camera.lens is not None:
        row["distortion_model"] = camera.lens.model
        row.update(camera.lens.coefficients)
    return row


def checked(estimate: PoseEstimate, options: EstimateOptions) -> None:
    """Raise :class:`EstimateError` for an estimate with no pose or too little confidence."""
    if not estimate.ok:
        raise EstimateError(estimate.error)
    if estimate.confidence < options.min_confidence:
        why = f"another orientation fits the lines {estimate.rival:.0%} as well"
        if estimate.focal_uncertainty is not None:
            why += (f"; the focal length's uncertainty turns the pose by "
                    f"{estimate.focal_uncertainty.degrees:.1f} deg")
        why += (f"; the vertical's and the wall's own lines point up to "
                f"{estimate.misfit:.1f} deg from the fitted frame")
        if not estimate.normal_seen:
            why += ("; no edges recede from the camera beyond chance: the wall's direction "
                    "rests on its horizontals alone")
        if estimate.upright < UPRIGHT_NOTED:
            why += (f"; another of its directions is nearly as upright: the vertical taken "
                    f"is up with probability {estimate.upright:.2f}")
        # what would settle it, as the estimator's own refusals say
        raise EstimateError(f"confidence {shown_below(estimate.confidence, 2)} is below the "
                            f"minimum {options.min_confidence:g} ({why}); "
                            f"{remedy(estimate.focal_uncertainty is not None)}")


def without_guides(reason: str) -> str:
    """A refusal's ``reason`` for a frame of a video or a bag, which takes no guides: the
    remedy ends at the focal length or the pose (``gsrwt estimate VIDEO --verticals`` is a
    usage error)."""
    for focal_estimated in (True, False):
        offered = remedy(focal_estimated)
        if reason.endswith(offered):
            return reason[:-len(offered)] + remedy(focal_estimated, guides=False)
    return reason


def estimated_values(estimate: PoseEstimate, camera: Intrinsics | None, width: int,
                     height: int, principal_point: tuple[float, float] | None = None
                     ) -> dict[str, Any]:
    """The sidecar values of an estimate: pose, focal length (or fx, fy), principal point,
    size."""
    assert estimate.pose is not None and estimate.focal is not None
    values: dict[str, Any] = {"pan": estimate.pose.pan, "tilt": estimate.pose.tilt,
                              "roll": estimate.pose.roll, "width": width, "height": height}
    used = camera_used(estimate, camera, width, height, principal_point)
    assert used is not None
    if used.fx == used.fy:
        values["focal"] = used.fx
    else:
        values.update(fx=used.fx, fy=used.fy)
    values.update(cx=used.cx, cy=used.cy)
    return values


def camera_used(estimate: PoseEstimate, camera: Intrinsics | None, width: int, height: int,
                principal_point: tuple[float, float] | None = None) -> Intrinsics | None:
    """The camera the estimate worked with (the given one, or the estimated focal length at
    the principal point), with the image's size; None if there is none."""
    if camera is not None:
        return Intrinsics(camera.fx, camera.fy, camera.cx, camera.cy, camera.skew, width,
                          height, camera.lens)
    if estimate.focal is None:
        return None
    cx, cy = principal_point or ((width - 1) / 2.0, (height - 1) / 2.0)
    return Intrinsics(estimate.focal, estimate.focal, cx, cy, width=width, height=height)


def estimate_row(estimate: PoseEstimate, source: str) -> dict[str, Any]:
    """The columns of an estimate other than its sidecar values; ``focal_sd`` where the
    segments estimated or refined the focal length: its standard deviation as a fraction of
    it (that of its logarithm, :class:`~gsrwt_cli.api.estimate.FocalUncertainty`)."""
    row: dict[str, Any] = {"confidence": round(estimate.confidence, 4),
                           "segments": estimate.segments, "inliers": estimate.inliers,
                           "focal_source": source}
    spread = estimate.focal_uncertainty
    if spread is not None and math.isfinite(spread.sigma):
        row["focal_sd"] = round(spread.sigma, 4)
    for name, point in zip(DIRECTION_NAMES, estimate.vanishing_points):
        if point is not None:
            row[f"vp_{name}_col"], row[f"vp_{name}_row"] = point
    return row


def guided_row(path: Path, values: Mapping[str, Any], where: str, orientation: int = 1
               ) -> dict[str, Any]:
    """The row of an image whose pose its guides show (``estimate --corners`` and the
    like): the pose and camera as a sidecar row, the focal length's source (``estimated``
    when the guides told it), the rectangle's aspect ratio and its source. The image's file
    is read for its size and EXIF only; the guides are of the photo as its EXIF
    ``orientation`` displays it (1: as stored). Raises
    :class:`~gsrwt_cli.inputs.records.RecordError` for bad guides."""
    own = {name: value for name, value in values.items() if name not in _POSE_VALUES}
    own, source = with_focal(path, own, where, orientation)
    size = image_file_size(path)
    if size is None:
        raise ValueError("cannot read the image's size")
    width, height = displayed_size(orientation, *size)
    if own.get("width") in (None, ""):
        own["width"], own["height"] = width, height
    posed, columns = guided_view_values(own, where, orientation)
    view = view_from_values(posed, where, orientation)
    row = {name: value for name, value in view.sidecar_values().items()
           if name in ("pan", "tilt", "roll", "focal", "fx", "fy", "cx", "cy", "width",
                       "height") and value is not None}
    row["roll"] = view.roll
    row["focal_source"] = columns.pop("focal_source", source)
    row.update(columns)
    return row


#: How a pose the corners ``--auto document`` found cannot give begins: the user gave no
#: corners, so the reason is not said of a field of theirs.
DOCUMENT_NO_POSE = "the document's corners give no pose"


def found_corners_reason(error: RecordError) -> str | None:
    """The reason of a guide's error on the corners ``--auto document`` found, said of the
    document (the user gave no corners); None for another field's."""
    return f"{DOCUMENT_NO_POSE}: {error.reason}" if error.field == "corners" else None


def document_values(path: Path, values: Mapping[str, Any], where: str,
                    options: EstimateOptions, image: np.ndarray | None = None
                    ) -> dict[str, Any]:
    """``values`` (their pose left out) with the ``corners`` of the document the image shows
    (``--auto document``: :func:`~gsrwt_cli.vision.document.find_document`), in the photo as
    displayed (``image``: the photo, when it is already read). Raises
    :class:`~gsrwt_cli.api.estimate.EstimateError`, saying why, when there is no clear one,
    or when, with the focal length known, the quadrilateral is no rectangle's image: the
    corners of the best-fitting rectangle seen by that camera miss them by more than
    :data:`MAX_DOCUMENT_RMS_PX` (root mean square)."""
    from ..vision.document import DocumentError, find_document  # only when asked for

    orientation = orientation_of(path, options)
    if image is None:
        image = read_image(path, options.max_input_pixels, orientation)
    try:
        found = find_document(image)
    except DocumentError as error:
        raise EstimateError(str(error)) from None
    own = {name: value for name, value in values.items() if name not in _POSE_VALUES}
    own["corners"] = found.corners_text()
    sized = dict(own)
    if sized.get("width") in (None, "") and sized.get("cx") in (None, ""):
        sized["height"], sized["width"] = image.shape[:2]
    camera = camera_for(path, sized, where, orientation, options.lens_profile)[0]
    if camera is not None:
        try:
            fit = guided_pose({"corners": own["corners"], "aspect": own.get("aspect")},
                              camera, None)
        except GuideError as error:
            raise EstimateError(f"{DOCUMENT_NO_POSE}: {error}") from None
        if fit.rms_px > MAX_DOCUMENT_RMS_PX:
            raise EstimateError(
                f"the largest quadrilateral is no rectangle seen by this camera: the best "
                f"rectangle's corners miss it by {fit.rms_px:.1f} px (rms; "
                f"{MAX_DOCUMENT_RMS_PX:g} allowed); give --corners")
    return own


def estimated_view_values(path: Path, values: Mapping[str, Any], where: str,
                          options: EstimateOptions
                          ) -> tuple[dict[str, Any], str, float, dict[str, Any]]:
    """An image's values with its pose estimated (``rectify --auto``): the values (lens and
    calibration file kept, the estimate's pose and intrinsics over them, the lensfun profile
    the estimate used added), where the focal length came from, the confidence, and the
    lens's ``lens_source`` and ``lens_profile``. Raises
    :class:`~gsrwt_cli.api.estimate.EstimateError` when the image cannot tell (or tells too
    little)."""
    estimate, camera, source, image, lens = estimate_file(path, values, where, options)
    height, width = image.shape[:2]
    del image
    checked(estimate, options)
    principal_point = (camera_for(path, values, where, orientation_of(path, options),
                                  options.lens_profile)[2]
                       if camera is None else None)
    merged = {name: value for name, value in values.items()
              if name not in (*_POSE_VALUES, *SENSOR_FIELDS, "focal", "fx", "fy")}
    merged.update(estimated_values(estimate, camera, width, height, principal_point))
    if values.get("fit") not in (None, "", "both"):  # --fit vertical or horizontal
        merged["pan"], merged["tilt"], merged["roll"] = fit_pose(
            merged["pan"], merged["tilt"], merged["roll"], values["fit"])
    if lens["lens_source"] == "lensfun" and camera is not None:  # the profile estimated with
        merged["distortion_model"] = camera.lens.model
        merged.update(camera.lens.coefficients)
    found = lens.pop("lines", None)
    if found is not None:  # --lens-from-lines: the lens taken, or why not
        if found.taken:
            merged.update(distortion_model="plumb_bob", k1=found.k1)
        lens["lens_profile"] = found.summary()
    return merged, source, round(estimate.confidence, 4), lens


# --------------------------------------------------------------------------------------------
# The batch of ``gsrwt estimate``
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class EstimateJob:
    """One image: its file, its name in the table (the relative path a sidecar matches), its
    raw camera values and where they came from, its picture's file (``--draw``), and an error
    known before reading it."""

    source: Path
    name: str
    values: dict[str, Any]
    where: str
    picture: Path | None = None
    error: str | None = None


def process_estimate(job: EstimateJob, options: EstimateOptions,
                     describe: Callable[[BaseException], str | None] | None = None,
                     picture_root: Path | None = None) -> dict[str, Any]:
    """The row of one image; never raises for a bad image (its row says what went wrong)."""
    row: dict[str, Any] = {"image": job.name}
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            if job.error is not None:
                raise EstimateError(job.error)
            if has_guides(job.values) or options.mode == "document":
                values = job.values
                corners_found = not has_guides(values)  # by --auto document, not given
                if corners_found:
                    values = _found_document(job, options, picture_root)
                    row["corners"] = values["corners"]
                try:
                    row.update(guided_row(job.source, values, job.where,
                                          orientation_of(job.source, options)), status="ok")
                except RecordError as error:
                    reason = found_corners_reason(error) if corners_found else None
                    if reason is None:
                        raise
                    raise EstimateError(reason) from None
                return row
            estimate, camera, source, image, lens = estimate_file(job.source, job.values,
                                                                  job.where, options)
            row.update(estimate_row(estimate, source))
            if options.lens_from_lines:
                row.update(lens_columns(lens, camera))
            height, width = image.shape[:2]
            principal_point = None
            if camera is None:
                principal_point = camera_for(job.source, job.values, job.where,
                                             orientation_of(job.source, options),
                                             options.lens_profile)[2]
            if job.picture is not None:
                from ..api.estimate_drawing import draw_estimate  # only when pictures are asked for

                used = camera_used(estimate, camera, width, height, principal_point)
                picture = draw_estimate(image, estimate, used)
                write_atomic(job.picture, encode_image(picture, ".png"), root=picture_root)
            del image
            checked(estimate, options)
            row.update(estimated_values(estimate, camera, width, height, principal_point))
            row["status"] = "ok"
    except Exception as error:  # every failure of one image is that image's row
        row.update(status="error", error=error_text(error, describe))
    return row


def _found_document(job: EstimateJob, options: EstimateOptions,
                    picture_root: Path | None) -> dict[str, Any]:
    """The job's values with the corners of its document (:func:`document_values`), and its
    picture (``--draw``: the document's outline, or why there is none) written."""
    if job.picture is None:
        return document_values(job.source, job.values, job.where, options)
    from ..api.estimate_drawing import draw_document  # only when pictures are asked for

    image = read_image(job.source, options.max_input_pixels, orientation_of(job.source, options))
    try:
        values = document_values(job.source, job.values, job.where, options, image)
    except EstimateError as error:
        write_atomic(job.picture, encode_image(draw_document(image, None, str(error)), ".png"),
                     root=picture_root)
        raise
    corners = np.array([[float(v) for v in point.split(",")]
                        for point in values["corners"].split()])
    write_atomic(job.picture, encode_image(draw_document(image, corners, "document"), ".png"),
                 root=picture_root)
    return values


class EstimateWorker(ProcessWorker):
    """One estimate worker's state: the options and where pictures go."""

    def __init__(self, options: EstimateOptions, picture_root: Path | None,
                 opencv_threads: int = 0) -> None:
        super().__init__(opencv_threads)
        self.options = options
        self.picture_root = picture_root

    def __call__(self, job: EstimateJob) -> dict[str, Any]:
        return process_estimate(job, self.options, picture_root=self.picture_root)


def run_estimates(jobs: list[EstimateJob], options: EstimateOptions, processes: int,
                  on_row: Callable[[dict[str, Any]], None], *, picture_root: Path | None = None,
                  context: multiprocessing.context.BaseContext,
                  on_progress: Callable[[], None] | None = None) -> int:
    """Estimate every job on :class:`~gsrwt_cli.batch.executor.ProcessExecutor` workers (a worker
    that dies costs only its image), handing rows to ``on_row`` in job order; returns how
    many failed. If the run is stopped (``KeyboardInterrupt``, say), the workers are
    stopped, every job still gets its row (``interrupted`` for those not done) and the
    exception goes on."""
    failed = 0

    def died(job: EstimateJob, reason: str) -> dict[str, Any]:
        return {"image": job.name, "status": "error", "error": reason}

    def stopped(index: int) -> dict[str, Any]:
        return {"image": jobs[index].name, "status": "interrupted",
                "error": "not done: the run was interrupted"}

    def deliver(row: dict[str, Any]) -> None:
        nonlocal failed
        failed += row.get("status") != "ok"
        on_row(row)

    executor: ProcessExecutor[EstimateJob, dict[str, Any]] = ProcessExecutor(
        EstimateWorker.in_own_process, (options, picture_root, 1 if processes > 1 else 0),
        max(1, min(processes, len(jobs))), on_death=died,
        context=context,
    )
    run_in_order(len(jobs), executor.map_unordered(jobs), deliver, stopped,
                 on_progress=on_progress)
    return failed
