"""The options of one ``gsrwt rectify`` run, shared by its workers and its reruns."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..imaging.images import DEFAULT_MAX_INPUT_PIXELS
from ..io.storage import Location

#: A function that words an error for the user, or returns None for the error's own text.
Describe = Callable[[BaseException], "str | None"]


@dataclass(frozen=True)
class Settings:
    """The options of one ``gsrwt rectify`` run, shared by all workers."""

    bbox: str | tuple[float, float, float, float] = "frontal"
    scale: float = 1.0
    px_per_unit: float | None = None
    max_stretch: float = 4.0
    max_pixels: float = 50e6
    max_size: tuple[int, int] | None = None
    interpolation: str = "linear"
    fill: float = 0.0
    alpha: bool = False
    quality: int = 95
    overwrite: bool = False
    dry_run: bool = False
    max_input_pixels: float = DEFAULT_MAX_INPUT_PIXELS
    antialias: bool = True
    root: Path | Location | None = None  # the output directory: nothing is written outside it
    #: Words an error in the caller's terms (a module-level function: it goes to workers).
    describe: Describe | None = None
