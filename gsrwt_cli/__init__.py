"""gsrwt: canonical frontal views of flat surfaces from pan-tilt camera images (GS-RWT)."""

from .camera import View, ViewError
from .geometry import GsrwtParameters, gsrwt_parameters

__version__ = "0.1.0"

__all__ = ["GsrwtParameters", "View", "ViewError", "__version__", "gsrwt_parameters"]
