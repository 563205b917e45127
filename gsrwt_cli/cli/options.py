"""Options and errors shared by several commands, defined once.

It imports only what every command needs (click, numpy): what one option needs (OpenCV's
interpolation flags, the edge stage) is imported by that option, when a command uses it.
"""

from __future__ import annotations

import os
import sys
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click

from ..base.messages import one_line, quote
from ..base.numerals import parse_decimal, parse_whole
from ..geometry.bounds import VIEW_FIELDS
from ..io.storage import Location, location
from ..tables.writer import FORMATS

if TYPE_CHECKING:
    from ..geometry.camera import View
    from ..inputs.records import RecordError
    from ..inputs.sidecar import Sidecar
    from ..io.targets import TargetError

F = TypeVar("F", bound=Callable[..., Any])


class PathOrUrl(click.Path):
    """A path (a :class:`~pathlib.Path`, checked as ``click.Path`` checks it) or a URL
    such as ``s3://bucket/run1/`` (a :class:`~gsrwt_cli.io.storage.Location`, checked by its
    store when used); ``file://`` URLs are paths."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(path_type=Path, **kwargs)

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        found = location(value) if isinstance(value, str) else value
        if isinstance(found, Location):
            return found
        return super().convert(str(found), param, ctx)


#: ``-j``: worker processes at most (a bound, so that a typo is not a fork bomb).
MAX_JOBS = 1024


class _AsciiNumber:
    """A number option read by ``parse`` (ASCII digits only: no ``+``, ``_``, space or other
    script's digits), then range-checked by the click range type it is mixed into."""

    parse: Callable[[str], float]

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        if isinstance(value, str):
            try:
                value = self.parse(value)
            except ValueError as error:
                self.fail(f"{error}, got {quote(value)}", param, ctx)  # type: ignore[attr-defined]
        return super().convert(value, param, ctx)  # type: ignore[misc]

    def _describe_range(self) -> str:
        if self.min is None and self.max is None:  # type: ignore[attr-defined]
            return ""
        return super()._describe_range()  # type: ignore[misc]


class Integer(_AsciiNumber, click.IntRange):
    """A whole-number option (:func:`~gsrwt_cli.base.numerals.parse_whole`), within ``min`` and
    ``max`` if given."""

    name = "integer"
    parse = staticmethod(parse_whole)


class Number(_AsciiNumber, click.FloatRange):
    """A number option: a finite decimal (:func:`~gsrwt_cli.base.numerals.parse_decimal`), within
    ``min`` and ``max`` if given."""

    name = "float"
    parse = staticmethod(parse_decimal)


#: The option type of each kind of value of :data:`VIEW_OPTIONS`.
OPTION_TYPES: dict[type, click.ParamType] = {float: Number(), int: Integer()}


class InputError(click.ClickException):
    """Bad input from the user (file, row, option): one line on stderr, exit code 2."""

    exit_code = 2

    def __init__(self, message: str) -> None:
        super().__init__(one_line(message))


class LocalPath(PathOrUrl):
    """A local path (``click.Path``) for an option that takes no URL: a URL (``s3://``) is
    refused in one line rather than taken for a local name (``s3:/bucket``)."""

    def convert(self, value: Any, param: click.Parameter | None,
                ctx: click.Context | None) -> Any:
        found = super().convert(value, param, ctx)
        if isinstance(found, Location):
            option = max(param.opts, key=len) if param is not None and param.opts else ""
            raise InputError(f"{option} {value}: is a URL; {option} takes a local path")
        return found


def report_error(message: str) -> None:
    """One ``Error: ...`` line on stderr: control characters escaped, length bounded."""
    click.echo("Error: " + one_line(message), err=True)


def view_from_options(values: dict[str, Any]) -> View:
    """The one view the view options describe, or an :class:`InputError` naming the option."""
    from ..inputs.records import RecordError, view_from_values

    try:
        return view_from_values(values, "options")
    except RecordError as error:
        raise InputError(option_message(error)) from None


def load_sidecar_option(sidecar: Path | None) -> Sidecar | None:
    """The ``--sidecar`` the user named, loaded (None without one; ``-``: standard input),
    or an :class:`InputError` saying what is wrong with the file."""
    if sidecar is None:
        return None
    from ..inputs.sidecar import SidecarError, load_sidecar, sidecar_from_text

    try:
        if str(sidecar) == "-":  # a pipe: gsrwt estimate ... | gsrwt rectify --sidecar -
            data = click.get_binary_stream("stdin").read()
            try:
                return sidecar_from_text(data.decode("utf-8"))
            except UnicodeDecodeError as error:
                raise InputError(f"--sidecar -: standard input is not UTF-8 text "
                                 f"({error.reason})") from None
        return load_sidecar(sidecar)
    except SidecarError as error:
        raise InputError(str(error)) from None
    except OSError as error:  # a store that cannot be reached (storage.StoreError)
        raise InputError(f"{sidecar}: cannot read ({error.strerror or error})") from None


def prepare_directory(directory: Path | Location, what: str) -> None:
    """Make ``directory`` and prove it writable (a temporary file made and removed), or
    raise InputError starting with ``what`` (the option and the name the user gave).

    On an object store, a probe object is written and removed below the prefix
    (:func:`~gsrwt_cli.io.storage.check_writable`): a missing bucket, refused credentials or an
    unreachable endpoint are found here, before any work."""
    if isinstance(directory, Location):
        from ..io.storage import check_writable

        try:
            check_writable(directory)
        except OSError as error:
            raise InputError(f"{what}: cannot write there ({error.strerror or error})") from None
        return
    blocker = next((p for p in [directory, *directory.parents] if p.exists()), None)
    if blocker is not None and not blocker.is_dir():
        raise InputError(f"{what}: cannot write there ({blocker} is not a directory)")
    try:
        directory.mkdir(parents=True, exist_ok=True)
        descriptor, probe = tempfile.mkstemp(
            dir=directory, prefix=f".gsrwt-probe.gsrwt-{os.getpid()}-", suffix=".part"
        )
        os.close(descriptor)
        os.unlink(probe)
    except OSError as error:
        reason = error.strerror or str(error)
        raise InputError(f"{what}: cannot write there ({reason})") from None


def prepare_table(name: str, option: str) -> None:
    """Before any work, make sure the table (or another file written at the end of the
    work) can be written at ``name`` (``-`` is standard output): not a directory, in a
    directory that exists or can be made and is writable (:func:`prepare_directory`), or
    below a prefix of a store that takes a write. Else an :class:`InputError` naming
    ``option``."""
    if name == "-":
        return
    table = location(name)
    if isinstance(table, Path) and table.is_dir():
        raise InputError(f"{option} {name}: is a directory; give the table's file name")
    prepare_directory(table.parent, f"{option} {name}")


def target_message(error: TargetError, option: str | None = None) -> str:
    """A refused output in the user's terms: ``option`` is the flag that named the file, if
    one did; an existing file tells how to replace it."""
    from ..io.targets import (  # only when something was refused: not on every start-up
        DirectoryTargetError,
        ExistingOutputError,
        InputOverwriteError,
        UncreatableDirectoryError,
        UnwritableFileError,
    )

    where = f"{option} {error.path}" if option else str(error.path)
    if isinstance(error, ExistingOutputError):
        return f"{where}: exists; use --overwrite to replace it"
    if isinstance(error, InputOverwriteError):
        return f"{where}: would overwrite an input; choose another output"
    if isinstance(error, DirectoryTargetError):
        return f"{where}: is a directory; give a file name"
    if isinstance(error, UncreatableDirectoryError):
        return f"{where}: cannot create it ({error.reason})"
    if isinstance(error, UnwritableFileError):
        return f"{where}: cannot write it ({error.reason})"
    return f"{where}: {error.reason}"


def make_output_directory(option: str, directory: Path) -> None:
    """Create the output directory the user named and prove it writable, or stop with one
    line saying why not."""
    from ..io.targets import TargetError
    from ..io.targets import make_output_directory as create_directory

    try:
        create_directory(directory)
    except TargetError as error:
        raise InputError(target_message(error, option)) from None
    prepare_directory(directory, f"{option} {directory}")


def format_option(func: F) -> F:
    """``--format``: table on a terminal, csv when stdout is a pipe."""
    return click.option(
        "--format",
        "-f",
        "fmt",
        type=click.Choice(FORMATS),
        default=None,
        help="Output format [default: table on a terminal, csv in a pipe].",
    )(func)


def resolve_format(fmt: str | None) -> str:
    """The chosen format, or the default for where stdout goes."""
    if fmt is not None:
        return fmt
    return "table" if sys.stdout.isatty() else "csv"


#: The view options: type and help of each of :data:`~gsrwt_cli.geometry.camera.VIEW_FIELDS`.
VIEW_OPTIONS: dict[str, tuple[type, str]] = {
    "pan": (float, "Pan in degrees, positive turns left."),
    "tilt": (float, "Tilt in degrees, positive tilts up."),
    "roll": (float, "Roll in degrees about the optical axis, positive leans the top right."),
    "focal": (float, "Focal length in pixels (fx = fy)."),
    "fx": (float, "Horizontal focal length in pixels (with --fy, instead of --focal)."),
    "fy": (float, "Vertical focal length in pixels (with --fx)."),
    "cx": (float, "Principal point column [default: image centre]."),
    "cy": (float, "Principal point row [default: image centre]."),
    "skew": (float, "Skew of the camera matrix, K[0, 1] [default: 0]."),
    "width": (int, "Image width in pixels."),
    "height": (int, "Image height in pixels."),
    "distance": (float, "Camera-to-wall distance (your unit)."),
}


def field_options(fields: dict[str, tuple[type, str]], camera_help: str) -> Callable[[F], F]:
    """``--camera FILE`` (with ``camera_help``), then one option per field of ``fields``
    (name: type and help), in its order."""
    def decorate(func: F) -> F:
        for name in reversed(fields):
            kind, text = fields[name]
            func = click.option(f"--{name}", type=OPTION_TYPES[kind], help=text)(func)
        return click.option("--camera", type=click.Path(dir_okay=False),
                            help=camera_help)(func)
    return decorate


#: ``--pan --tilt --roll --focal --fx --fy --cx --cy --skew --width --height --distance``
#: and ``--camera``: one option for each field of :data:`~gsrwt_cli.geometry.camera.VIEW_FIELDS`.
view_options = field_options(
    {name: VIEW_OPTIONS[name] for name in VIEW_FIELDS},
    "Calibration file (OpenCV YAML/XML or ROS camera_info) with the intrinsics and lens; the "
    "view options and sidecar fields override it.")


#: The guide options of guided correction, as fields of a sidecar row too
#: (:mod:`~gsrwt_cli.inputs.guides`), with their help.
GUIDE_OPTIONS = {
    "corners": ("Four corners of a rectangle upright on the wall, \"x1,y1 x2,y2 x3,y3 x4,y4\" "
                "in pixels (top-left, top-right, bottom-right, bottom-left): the pose from "
                "them, and the focal length when none is given and the view is oblique "
                "enough."),
    "aspect": ("The rectangle's width over height, W:H or a number (A4 upright: 210:297) "
               "[default: estimated from the corners]."),
    "verticals": ("Two or more segments along vertical edges of the wall, "
                  "\"x1,y1,x2,y2;x1,y1,x2,y2;...\" in pixels."),
    "horizontals": "Two or more segments along horizontal edges of the wall, as --verticals.",
}


def _checked_guide(ctx: click.Context, param: click.Parameter, value: str | None
                   ) -> str | None:
    """A guide option's text, refused (exit 2, naming the option) unless it reads."""
    if value is None:
        return None
    from ..geometry.guides import GuideError
    from ..inputs.guides import parse_aspect, parse_corners, parse_segments

    try:
        if param.name == "corners":
            parse_corners(value)
        elif param.name == "aspect":
            parse_aspect(value)
        else:
            parse_segments(value, str(param.name))
    except GuideError as error:
        raise InputError(f"option --{param.name}: {error}") from None
    return value


def guide_options(func: F) -> F:
    """``--corners --aspect --verticals --horizontals --fit``: the pose shown by hand."""
    func = click.option("--fit", type=click.Choice(("both", "vertical", "horizontal")),
                        default=None,
                        help="What the output straightens: both (the frontal view), vertical "
                             "(verticals vertical and parallel, the horizontal perspective "
                             "kept: a keystone fix) or horizontal [default: both].")(func)
    for name in reversed(GUIDE_OPTIONS):
        func = click.option(f"--{name}", callback=_checked_guide,
                            help=GUIDE_OPTIONS[name])(func)
    return func


def interpolation_option(func: F) -> F:
    """``--interpolation``: how output pixels are sampled from the input."""
    from ..imaging.images import INTERPOLATIONS

    return click.option("--interpolation", type=click.Choice(tuple(INTERPOLATIONS)),
                        default="linear", show_default=True)(func)


def quality_option(func: F) -> F:
    """``--quality``: of JPEG and WebP outputs."""
    return click.option("--quality", type=Integer(1, 100), default=95, show_default=True,
                        help="JPEG and WebP quality.")(func)


def jobs_option(func: F) -> F:
    """``-j/--jobs``: worker processes (at most :data:`MAX_JOBS`)."""
    return click.option("-j", "--jobs", type=Integer(1, MAX_JOBS), default=None,
                        help="Worker processes [default: all cores].")(func)


def max_input_pixels_option(func: F) -> F:
    """``--max-input-pixels``: inputs whose header claims more pixels are refused undecoded."""
    return click.option("--max-input-pixels", default="300M", show_default=True,
                        help="Refuse, before decoding it, an input whose header claims more "
                             "pixels.")(func)


#: ``--orientation``'s choices: the photo as its EXIF orientation displays it, or as stored.
ORIENTATION_CHOICES = ("exif", "ignore")


def orientation_option(func: F, names: tuple[str, ...] = ("--orientation",
                                                          "--exif-orientation")) -> F:
    """``--orientation`` (also ``--exif-orientation``; ``gsrwt lines``, whose
    ``--orientation`` is the segments', only that), the ``exif_orientation`` parameter: apply
    the EXIF orientation (default) or use the stored pixels."""
    return click.option(*names, "exif_orientation", type=click.Choice(ORIENTATION_CHOICES),
                        default="exif", show_default=True,
                        help="exif: turn the photo as its EXIF orientation says, as viewers "
                             "show it (pan, tilt, roll, cx, cy and pixels are of the photo as "
                             "displayed; a --camera file's of the sensor, turned with it); "
                             "ignore: the pixels as stored.")(func)


#: ``--lens-profile``'s choices (:data:`~gsrwt_cli.inputs.lensfun.LENS_PROFILE_MODES`, named
#: here too: the options load without numpy).
LENS_PROFILE_CHOICES = ("auto", "lensfun", "off")


def lens_profile_option(func: F) -> F:
    """``--lens-profile auto|lensfun|off``: lensfun's profile for photos whose lens is given
    nowhere (:mod:`~gsrwt_cli.inputs.lensfun`)."""
    return click.option("--lens-profile", type=click.Choice(LENS_PROFILE_CHOICES),
                        default="auto", show_default=True,
                        help="For photos whose lens no calibration file or lens column "
                             "gives: auto: the profile lensfun's database has for their EXIF "
                             "camera and lens, when the extra gsrwt[lenses] is installed; "
                             "lensfun: the same, and an error without the extra; off: a "
                             "pinhole.")(func)


def lens_from_lines_option(func: F) -> F:
    """``--lens-from-lines``: k1 from the image's straight lines (:mod:`~gsrwt_cli.api.
    lens_lines`), for photos whose lens nothing else gives."""
    return click.option("--lens-from-lines", is_flag=True,
                        help="Estimate radial distortion (k1, OpenCV's plumb_bob) from the "
                             "image's long straight lines, with the pose, for wide angles "
                             "without a calibration: taken only when the lines pin it down "
                             "and straightening them clearly helps, else a pinhole, the "
                             "table saying why. A calibration file, lens columns or a "
                             "lensfun profile take precedence.")(func)


def check_lens_profile(mode: str) -> None:
    """Refuse ``--lens-profile lensfun`` without the extra, as a usage error."""
    from ..inputs.lensfun import lensfun_installed

    if mode == "lensfun" and not lensfun_installed():
        raise click.BadParameter("lensfun needs the extra: pip install 'gsrwt[lenses]'",
                                 param_hint="'--lens-profile'")


def quiet_option(what: str) -> Callable[[F], F]:
    """``-q/--quiet``: ``what`` the command leaves out (its summary, its progress bar)."""
    return click.option("-q", "--quiet", is_flag=True, help=what)


def edge_threshold_option(func: F, default: float | None = None,
                          text: str = "Sobel magnitude of an edge pixel.") -> F:
    """``--edge-threshold``: the Sobel magnitude of an edge pixel (lines, match); ``default``
    None is the thesis's raw threshold."""
    if default is None:
        from ..vision.landmarks import DEFAULT_EDGE_THRESHOLD

        default = DEFAULT_EDGE_THRESHOLD
    return click.option("--edge-threshold", type=Number(min=0, min_open=True),
                        default=default, show_default=True, help=text)(func)


def images_argument(func: F) -> F:
    """``IMAGE...``: image files and directories of images, paths or URLs (lines, match)."""
    return click.argument("images", nargs=-1, required=True, type=PathOrUrl(),
                          metavar="IMAGE...")(func)


def draw_option(what: str) -> Callable[[F], F]:
    """``--draw DIR`` of the landmark commands: the frontal views with ``what`` drawn in."""
    return click.option("--draw", type=LocalPath(file_okay=False),
                        help=f"Write the frontal views with the {what} drawn into this "
                             "directory.")


def raw_views_sidecar_option(func: F) -> F:
    """``--sidecar`` of the landmark commands: parameters of views to rectify first."""
    return click.option("--sidecar", type=PathOrUrl(dir_okay=False),
                        help="Parameters of raw views (as for rectify); images without are "
                             "taken as frontal already.")(func)


def option_message(error: RecordError) -> str:
    """A record error about values given as options, phrased in terms of the options."""
    if error.field is None:
        return error.reason.replace("missing field '", "missing option --").replace("'", "", 1)
    return f"option --{error.field}: {error.reason}"


def view_defaults(kwargs: dict[str, Any]) -> dict[str, Any]:
    """The view options the user gave, as fallback values for sidecar records."""
    return {name: kwargs[name] for name in (*VIEW_FIELDS, "camera", *GUIDE_OPTIONS, "fit")
            if kwargs.get(name) is not None}


class AutoModeCommand(click.Command):
    """A command whose ``--auto`` names its mode or stands alone: ``--auto document`` and
    ``--auto=document`` pick a mode, a bare ``--auto`` is the first mode (``lines``). The
    word after ``--auto`` is its mode only when it names one, so ``rectify --auto DIR``
    still reads ``DIR`` as an input (a file named like a mode: ``./document``)."""

    auto_modes: tuple[str, ...] = ()

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        words: list[str] = []
        rest = list(args)
        while rest:
            word = rest.pop(0)
            if word == "--":
                words += [word, *rest]
                break
            if word == "--auto":
                mode = rest.pop(0) if rest and rest[0] in self.auto_modes else self.auto_modes[0]
                word = f"--auto={mode}"
            words.append(word)
        return super().parse_args(ctx, words)


def auto_mode_command(modes: tuple[str, ...]) -> type[AutoModeCommand]:
    """A :class:`AutoModeCommand` class whose ``--auto`` takes ``modes`` (the first alone)."""
    return type("AutoCommand", (AutoModeCommand,), {"auto_modes": tuple(modes)})
