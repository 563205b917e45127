"""The options of one ``gsrwt rectify`` run, shared by its workers and its reruns."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..geometry.framing import DEFAULT_FRAMING, Framing
from ..imaging.images import DEFAULT_MAX_INPUT_PIXELS
from ..io.storage import Location

#: A function that words an error for the user, or returns None for the error's own text.
Describe = Callable[[BaseException], "str | None"]


@dataclass(frozen=True)
class Settings:
    """The options of one ``gsrwt rectify`` run, shared by all workers."""

    framing: Framing = DEFAULT_FRAMING  # the output's rectangle and size
    interpolation: str = "linear"
    fill: float = 0.0
    alpha: bool = False
    quality: int = 95
    overwrite: bool = False
    dry_run: bool = False
    max_input_pixels: float = DEFAULT_MAX_INPUT_PIXELS
    antialias: bool = True
    #: ``exif``: the photo as its EXIF orientation displays it; ``ignore``: the stored pixels.
    orientation: str = "exif"
    #: Carry the input's EXIF to the output, with gsrwt's record in XMP (``--strip-metadata``:
    #: False, nothing but the pixels, and a JPEG's colour profile).
    metadata: bool = True
    #: ``--lens-profile``: ``auto``, ``lensfun`` or ``off`` (:mod:`~gsrwt_cli.inputs.lensfun`).
    lens_profile: str = "auto"
    #: ``--lens-from-lines``: k1 from the image's lines where no lens is given nor profiled.
    lens_from_lines: bool = False
    root: Path | Location | None = None  # the output directory: nothing is written outside it
    #: Words an error in the caller's terms (a picklable callable: it goes to workers).
    describe: Describe | None = None
    #: The settings of an image whose pose the photo itself gives (``--auto``, guides), where
    #: they differ: without ``--bbox`` its frame is the whole wall it shows (``full``,
    #: capped), while a given pose keeps the thesis's frame. None: these settings for all.
    from_photo: Settings | None = None

    def of_image(self, pose_from_photo: bool) -> Settings:
        """The settings of one image: :attr:`from_photo` when its pose comes from the photo
        and they are set, else these."""
        return self.from_photo if pose_from_photo and self.from_photo is not None else self
