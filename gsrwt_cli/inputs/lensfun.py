"""Lens profiles from lensfun's database: a photo's EXIF camera, lens and focal length find
its distortion profile, which becomes the view's lens (issue 25, item 3).

Which lens an image gets, in order (its ``lens_source``):

1. ``sidecar``: its values give lens columns (``k1``, ..., ``distortion_model``) from a
   sidecar row, the YAML beside the image or the options, even all zero (a lens declared a
   pinhole), over a calibration file's;
2. ``camera``: a calibration file (``--camera``, a ``camera`` column) gives its lens;
3. ``lensfun``: lensfun's database has a profile of the EXIF's camera and lens at its focal
   length (:func:`find_profile`), converted by
   :func:`~gsrwt_cli.geometry.lensfun_models.lens_from_lensfun`;
4. ``none``: a pinhole, as before (no extra installed, no EXIF, not in the database).

lensfunpy (the optional extra ``gsrwt[lenses]``, which ships lensfun's database) is
imported on first use, and only its bundled database is read (``load_common=False``: the
same profiles on every machine, whatever lensfun the system has). Without it a photo simply
gets no profile: never an error. The calibration's aspect ratio, which lensfun's
normalisation needs and lensfunpy does not expose, is read from the same bundled XML files.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..geometry.lens import LENS_FIELDS
from ..geometry.lensfun_models import (
    DEFAULT_ASPECT,
    LENSFUN_MODELS,
    LensfunModelError,
    lens_from_lensfun,
    lensfun_unit_px,
)
from .exif import ExifCamera, camera_from_exif

#: ``--lens-profile``: ``auto`` (lensfun's database when the extra is installed), ``lensfun``
#: (the same, asked for: the command refuses to run without the extra), ``off`` (never).
LENS_PROFILE_MODES = ("auto", "lensfun", "off")
#: A focal length this far outside the lens's range (below its shortest, above its longest)
#: means EXIF names another lens: no profile.
FOCAL_SLACK = (0.95, 1.05)
#: The fields whose presence in an image's values means its lens is given (``sidecar``).
LENS_GIVERS = (*LENS_FIELDS, "distortion_model")


def lens_source_of(values: Mapping[str, Any]) -> str | None:
    """``sidecar`` (lens columns given), ``camera`` (a calibration file's lens), or None:
    the lens is given nowhere, and lensfun may be asked."""
    if any(values.get(name) not in (None, "") for name in LENS_GIVERS):
        return "sidecar"
    if values.get("camera"):
        return "camera"
    return None


@functools.lru_cache(maxsize=1)
def lensfun_installed() -> bool:
    """Whether lensfunpy (the extra ``gsrwt[lenses]``) can be imported (not importing it)."""
    return importlib.util.find_spec("lensfunpy") is not None


@dataclass(frozen=True)
class LensProfile:
    """A distortion profile of lensfun's database at one focal length: the ``camera`` and
    ``lens`` as lensfun names them, the ``model`` (poly3, poly5, ptlens) and its ``terms``,
    the camera's crop factor ``crop``, the calibration's ``lens_crop`` and ``lens_aspect``
    and the ``focal_mm`` it was interpolated at."""

    camera: str
    lens: str
    model: str
    terms: tuple[float, ...]
    crop: float
    lens_crop: float
    lens_aspect: float
    focal_mm: float

    def name(self) -> str:
        return f"{self.lens} at {self.focal_mm:g} mm on {self.camera}"


@functools.lru_cache(maxsize=1)
def _database() -> Any:
    import lensfunpy

    return lensfunpy.Database(load_common=False)


@functools.lru_cache(maxsize=1)
def _database_files() -> tuple[tuple[Path, str], ...]:
    """The bundled database's XML files and their text (about 5 MB, read once)."""
    import lensfunpy

    return tuple((path, path.read_text(encoding="utf-8")) for path in sorted(
        (Path(lensfunpy.__file__).parent / "db_files").glob("*.xml")))


@functools.lru_cache(maxsize=256)
def _aspect_ratio(maker: str, model: str, crop: float) -> float:
    """The calibration aspect ratio (long side over short) of the bundled lens ``maker``
    ``model`` calibrated at crop factor ``crop`` (as lensfun's float holds it), 3:2 when the
    database names none: only the files that name the model are parsed."""
    import xml.etree.ElementTree as ElementTree
    from xml.sax.saxutils import escape

    import numpy as np

    named = f">{escape(model)}</model>"
    for _, text in _database_files():
        if named not in text:
            continue
        for lens in ElementTree.fromstring(text).iter("lens"):
            if (maker not in [e.text for e in lens.findall("maker")]
                    or model not in [e.text for e in lens.findall("model")]
                    or float(np.float32(lens.findtext("cropfactor", "nan"))) != crop):
                continue  # (a name in any language: lensfun gives the locale's)
            ratio_text = (lens.findtext("aspect-ratio") or "").strip()
            width, _, height = ratio_text.partition(":")
            try:
                ratio = float(width) / float(height) if height else float(ratio_text)
            except (ValueError, ZeroDivisionError):
                return DEFAULT_ASPECT
            return max(ratio, 1 / ratio) if ratio > 0 and math.isfinite(ratio) else (
                DEFAULT_ASPECT)
    return DEFAULT_ASPECT


def _named(maker: str, model: str) -> str:
    return model if model.lower().startswith(maker.lower()) else f"{maker} {model}".strip()


def find_profile(exif: ExifCamera) -> LensProfile | None:
    """The rectilinear distortion profile lensfun's database has for the EXIF's camera and
    lens at its focal length, or None. The camera is lensfun's best match of make and model;
    the lens its best match of lens make and model among the camera's mounts, or, when EXIF
    names no lens, the camera's only lens (a compact's fixed lens); the focal length EXIF's
    ``FocalLength`` (a prime's own when absent), within the lens's range
    (:data:`FOCAL_SLACK`). Never raises."""
    try:
        return _find_profile(exif)
    except Exception:  # noqa: BLE001 - a third-party library's lookup: no profile
        return None


def _find_profile(exif: ExifCamera) -> LensProfile | None:
    database = _database()
    cameras = database.find_cameras(exif.make or None, exif.model)
    if not cameras:
        return None
    camera = cameras[0]
    if exif.lens_model:
        lenses = database.find_lenses(camera, exif.lens_make or None, exif.lens_model)
    else:
        lenses = database.find_lenses(camera)
        lenses = lenses if len(lenses) == 1 else []
    if not lenses:
        return None
    lens = lenses[0]
    if getattr(lens.type, "name", "") != "RECTILINEAR":
        return None  # a fisheye's profile is of its own projection
    focal = exif.focal_mm
    if focal is None and lens.min_focal and lens.min_focal == lens.max_focal:
        focal = lens.min_focal
    if focal is None or (lens.min_focal and lens.max_focal and not (
            FOCAL_SLACK[0] * lens.min_focal <= focal <= FOCAL_SLACK[1] * lens.max_focal)):
        return None  # (lensfun would take its nearest calibration: another lens, most likely)
    calibration = lens.interpolate_distortion(focal)
    if calibration is None:
        return None
    model = calibration.model.name.lower()
    if model not in LENSFUN_MODELS:
        return None
    count = {"poly3": 1, "poly5": 2, "ptlens": 3}[model]
    aspect = _aspect_ratio(lens.maker, lens.model, float(lens.crop_factor))
    return LensProfile(_named(camera.maker, camera.model), _named(lens.maker, lens.model),
                       model, tuple(float(t) for t in calibration.terms[:count]),
                       float(camera.crop_factor), float(lens.crop_factor), aspect, float(focal))


def _focal_px(values: Mapping[str, Any]) -> float | None:
    """The focal length in pixels the values give (``fx``/``fy`` or ``focal``), None when
    they give none in pixels or not as numbers (the view's own checks report bad ones)."""
    try:
        if values.get("fx") not in (None, "") and values.get("fy") not in (None, ""):
            focal = math.sqrt(float(values["fx"]) * float(values["fy"]))
        elif values.get("focal") not in (None, ""):
            focal = float(values["focal"])
        else:
            return None
    except (TypeError, ValueError, OverflowError):
        return None
    return focal if math.isfinite(focal) and focal > 0 else None


def with_lens_profile(head: bytes | None, size: tuple[int, int] | None,
                      values: Mapping[str, Any], mode: str = "auto"
                      ) -> tuple[dict[str, Any], str, str | None]:
    """An image's values with its lens resolved, its ``lens_source`` and the profile's
    ``lens_profile`` cell (module docstring).

    ``head``: the first bytes of the image file (its EXIF; None: not read, as when the lens
    is given or lensfun is not installed); ``size``: the image's stored ``(width, height)``
    (lensfun's normalisation; the same for the photo turned a quarter). A profile becomes
    the values' ``distortion_model`` and coefficients for the focal length in pixels the
    values give, centred on the principal point (lensfun's is the image's centre, the
    default principal point). ``mode``: :data:`LENS_PROFILE_MODES` (``off``: no profile).
    """
    values = dict(values)
    given = lens_source_of(values)
    if given is not None:
        return values, given, None
    if mode == "off":
        return values, "none", None
    focal = _focal_px(values)
    if head is None or size is None or focal is None or not lensfun_installed():
        return values, "none", None
    exif = camera_from_exif(head)
    profile = None if exif is None else find_profile(exif)
    if profile is None:
        return values, "none", None
    width, height = size
    try:
        unit = lensfun_unit_px(width, height, profile.crop, profile.lens_crop,
                               profile.lens_aspect)
        conversion = lens_from_lensfun(profile.model, profile.terms, focal, unit,
                                       math.hypot(width - 1, height - 1) / 2)
    except LensfunModelError:
        return values, "none", None
    values["distortion_model"] = conversion.lens.model
    values.update(conversion.lens.coefficients)
    how = (f"{profile.model} exact" if conversion.exact else
           f"{profile.model} fitted as {conversion.lens.model}, "
           f"{conversion.residual_px:.2f} px")
    return values, "lensfun", f"{profile.name()}: {how}"


def needs_exif(values: Mapping[str, Any], mode: str = "auto") -> bool:
    """Whether finding the image's lens reads its EXIF: no lens given, profiles not ``off``,
    lensfun installed."""
    return mode != "off" and lens_source_of(values) is None and lensfun_installed()
