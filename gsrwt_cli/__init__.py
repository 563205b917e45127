"""gsrwt: canonical frontal views of flat surfaces from pan-tilt camera images (GS-RWT)."""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: The package's API, each name imported from its module when first used: ``gsrwt --version``
#: and every command import only what they need (numpy and OpenCV take most of a start-up).
_API = {
    "Framing": "geometry.framing",
    "GsrwtParameters": "geometry.gsrwt",
    "GuidedPose": "geometry.guides",
    "Intrinsics": "geometry.camera",
    "Lens": "geometry.camera",
    "Plan": "geometry.framing",
    "Pose": "geometry.camera",
    "PoseEstimate": "api.estimate",
    "View": "geometry.camera",
    "ViewError": "geometry.camera",
    "estimate_pose": "api.estimate",
    "gsrwt_parameters": "geometry.gsrwt",
    "load_camera": "inputs.calibration",
    "plan_image": "api.rectify",
    "pose_from_corners": "geometry.guides",
    "pose_from_segments": "geometry.guides",
    "read_image": "imaging.images",
    "rectify_image": "api.rectify",
    "render_view": "batch.render_jobs",
}

__all__ = [*sorted(_API), "__version__"]


def __getattr__(name: str) -> Any:
    """PEP 562: the API names of :data:`_API`, imported on first use."""
    if name not in _API:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_API[name]}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_API})
