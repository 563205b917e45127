"""``--lens-from-lines`` measured: the plumb-line k1 on renders through OpenCV's lens model,
and what it does to the pose estimates of real pinhole photos (the York Urban DB's training
half, 51 photos with true orientations).

- **Renders** (:mod:`tests.helpers.lens_renders`: box rooms through ``cv2.projectPoints``
  with k1 only): per k1 in [-0.3, 0.1] and several poses, the k1 found and its error, the
  gate's verdict, and the pose's errors (vertical and wall normal, degrees) with the lens and
  as a pinhole; with the focal length given and estimated.
- **York** (calibrated focal length and principal point, as ``benchmarks/bench_real_photos.py``
  runs them; and with no focal length): per photo, the errors without and with
  ``--lens-from-lines`` (``benchmarks/real_photos.py``'s measures), the gate's verdict and
  statistics; the photos where the lens was taken and whether their error grew.

    python benchmarks/bench_lens_lines.py [PATH-TO-york-urban-train] [--renders-only]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

REPOSITORY = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPOSITORY))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_real_photos as york  # noqa: E402
import real_photos as measure  # noqa: E402

from gsrwt_cli.api.estimate import estimate_pose  # noqa: E402
from gsrwt_cli.api.lens_lines import estimate_with_lens_from_lines  # noqa: E402
from gsrwt_cli.geometry.camera import Intrinsics  # noqa: E402
from gsrwt_cli.imaging.images import read_image  # noqa: E402
from tests.helpers.estimate_scenes import angle_between  # noqa: E402
from tests.helpers.lens_renders import render_distorted_room  # noqa: E402

DEFAULT_DATA = REPOSITORY.parent / "shared" / "data" / "york-urban-train"
#: The renders: k1, pan, tilt, roll, focal length (640x480).
RENDERS = [
    (k1, pan, tilt, roll, focal)
    for k1 in (-0.3, -0.2, -0.1, -0.05, 0.0, 0.05, 0.1)
    for pan, tilt, roll, focal in ((15, -8, 3, 700), (-25, 10, -5, 650), (5, 4, 0, 800))
]


def _pose_errors(estimate, vertical: np.ndarray, normal: np.ndarray) -> tuple[float, float]:
    if estimate.world_from_camera is None:
        return (90.0, 90.0)
    return (angle_between(estimate.world_from_camera[0], vertical),
            angle_between(estimate.world_from_camera[2], normal))


def renders() -> None:
    print("Renders (640x480, box rooms through cv2.projectPoints with k1):")
    print("focal  | k1 true |  k1 found   sigma  | err   | taken | pose err lens (vert, wall) "
          "| pinhole")
    worst: dict[str, float] = {}
    for known in (True, False):
        for seed, (k1, pan, tilt, roll, focal) in enumerate(RENDERS):
            shot = render_distorted_room(pan, tilt, roll, k1=k1, focal=focal, seed=seed)
            camera = (Intrinsics(focal, focal, shot.cx, shot.cy, width=640, height=480)
                      if known else None)
            estimate, found = estimate_with_lens_from_lines(shot.image, camera)
            pinhole = estimate_pose(shot.image, camera)
            # k1 at the true focal length (the estimate's is normalised at its own)
            k1_found = (found.k1 if known or not found.taken
                        else found.at_focal(focal).k1)
            error = abs(k1_found - k1)
            lens_errors = _pose_errors(estimate, shot.vertical, shot.wall_normal)
            pin_errors = _pose_errors(pinhole, shot.vertical, shot.wall_normal)
            key = "given" if known else "estimated"
            if found.taken:
                worst[key] = max(worst.get(key, 0.0), error)
            print(f"{key:9s} | {k1:+.2f} | {k1_found:+.4f} {found.sigma:.4f} | {error:.4f} | "
                  f"{'yes' if found.taken else 'no ':5s} | {lens_errors[0]:5.2f} "
                  f"{lens_errors[1]:5.2f} | {pin_errors[0]:5.2f} {pin_errors[1]:5.2f}"
                  + ("" if found.taken else f"   ({found.reason})"))
    for key, value in worst.items():
        print(f"worst k1 error where taken, focal {key}: {value:.4f}")


def _errors(estimate, true: measure.SceneDirections) -> measure.ImageErrors:
    if estimate.pose is None:
        return measure.image_errors(None, true)
    pose = estimate.pose
    return measure.image_errors(measure.directions_from_pose(pose.pan, pose.tilt, pose.roll),
                                true)


def york_photos(data: Path) -> None:
    truth = york.read_truth(data)
    for known in (True, False):
        print(f"\nYork Urban training half ({data}), focal length "
              f"{'calibrated' if known else 'estimated'}:")
        taken, grew, refusals = [], [], {}
        seconds = 0.0
        for name, row in sorted(truth.items()):
            image = read_image(data / "images" / name)
            height, width = image.shape[:2]
            camera = (Intrinsics(float(row["focal_px"]), float(row["focal_px"]),
                                 float(row["cx"]), float(row["cy"]), width=width,
                                 height=height) if known else None)
            started = time.process_time()
            estimate, found = estimate_with_lens_from_lines(image, camera)
            seconds += time.process_time() - started
            pinhole = estimate_pose(image, camera)
            true = york.true_directions(row)

            before, after = _errors(pinhole, true), _errors(estimate, true)
            if found.taken:
                taken.append(name)
                if max(after.vertical - before.vertical, after.wall - before.wall) > 0.05:
                    grew.append(name)
            else:
                why = (found.reason or "").split(":")[0]
                refusals[why] = refusals.get(why, 0) + 1
            print(f"  {name:24s} pinhole {before.vertical:6.2f} {before.wall:6.2f} | lines "
                  f"{after.vertical:6.2f} {after.wall:6.2f} | {found.summary()}")
        print(f"  taken {len(taken)} of {len(truth)}: {', '.join(taken) or '-'}; error grew "
              f"(> 0.05 deg) on {len(grew)}: {', '.join(grew) or '-'}")
        print("  refused: " + "; ".join(f"{count} {why}" for why, count in
                                        sorted(refusals.items(), key=lambda kv: -kv[1])))
        print(f"  CPU per photo (lens search and the estimate with it): "
              f"{seconds / len(truth):.2f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--renders-only", action="store_true")
    parser.add_argument("--york-only", action="store_true")
    arguments = parser.parse_args()
    if not arguments.york_only:
        renders()
    if not arguments.renders_only:
        if not (arguments.data / "truth.csv").is_file():
            raise SystemExit(f"no York Urban data at {arguments.data}")
        york_photos(arguments.data)


if __name__ == "__main__":
    import warnings

    warnings.simplefilter("ignore")
    with np.errstate(all="ignore"):
        main()
