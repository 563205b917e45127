"""Real cameras: roll, fx != fy, skew and lens distortion, checked against a camera built from
OpenCV's own projection functions (not the project's) and from the words of docs/CONVENTIONS.md.

The camera's axes come from ``camera_axes`` of ``tests/helpers/camera.py`` (pan, tilt, then
roll about the optical axis so that the top leans right); rays become pixels through
``cv2.projectPoints`` (``cv2.fisheye.projectPoints``) and pixels rays through
``cv2.undistortPointsIter`` (``cv2.fisheye.undistortPoints``). The camera image is rendered
from a wall texture with it; the reference of the rectified view is one ``cv2.remap`` of that
image through it.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from gsrwt_cli import View
from gsrwt_cli.geometry.lens import Lens
from gsrwt_cli.tables.rows import params_row
from tests.helpers.camera import camera_axes
from tests.helpers.cli import run_gsrwt
from tests.helpers.images import psnr, smooth_texture
from tests.helpers.tables import read_table

WIDTH, HEIGHT, DISTANCE = 320, 240, 10.0
TEXTURE = smooth_texture(700, 900, 21)
CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 60, 1e-12)


class OpenCVCamera:
    """A camera at the origin looking at the wall ``Z = DISTANCE`` (world X up, Y right)."""

    def __init__(self, pan, tilt, roll, fx, fy, cx, cy, skew=0.0, model=None, coefficients=()):
        up, right, forward = camera_axes(pan, tilt, roll)
        self.camera_from_world = np.stack([right, -up, forward])  # OpenCV axes: x right, y down
        self.k = np.array([[fx, skew, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        self.model, self.coefficients = model, np.array(coefficients, dtype=np.float64)
        self.focal = math.sqrt(fx * fy)
        self.axis_point = DISTANCE * forward[:2] / forward[2]

    def pixels_of_wall(self, wall_xy: np.ndarray) -> np.ndarray:
        """Pixels of wall points ``(X, Y)``; NaN for points behind the camera."""
        world = np.column_stack([wall_xy, np.full(len(wall_xy), DISTANCE)])
        camera = world @ self.camera_from_world.T
        behind = camera[:, 2] <= 1e-9
        camera[behind, 2] = 1.0
        rays = (camera / camera[:, 2:3])[:, None, :]
        zero = np.zeros(3)
        if self.model == "equidistant":
            distorted, _ = cv2.fisheye.projectPoints(rays, zero, zero, np.eye(3),
                                                     self.coefficients)
        elif self.model is not None:
            distorted, _ = cv2.projectPoints(rays, zero, zero, np.eye(3), self.coefficients)
        else:
            distorted = rays[:, :, :2]
        normalized = distorted.reshape(-1, 2)
        pixels = normalized @ self.k[:2, :2].T + self.k[:2, 2]
        pixels[behind] = np.nan
        return pixels

    def wall_of_pixels(self, pixels: np.ndarray) -> np.ndarray:
        """Wall points ``(X, Y)`` the pixels see (NaN where they look away from the wall)."""
        normalized = np.column_stack([pixels, np.ones(len(pixels))]) @ np.linalg.inv(self.k).T
        points = normalized[:, None, :2].copy()
        if self.model == "equidistant":
            ideal = cv2.fisheye.undistortPoints(points, np.eye(3), self.coefficients,
                                                criteria=CRITERIA)
        elif self.model is not None:
            ideal = cv2.undistortPoints(points, np.eye(3), self.coefficients, None, None, None,
                                            CRITERIA)
        else:
            ideal = points
        rays = np.column_stack([ideal.reshape(-1, 2), np.ones(len(pixels))])
        world = rays @ self.camera_from_world  # camera_from_world^T applied to each ray
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(world[:, 2] > 1e-9, DISTANCE / world[:, 2], np.nan)
        return world[:, :2] * t[:, None]

    def texture_coordinates(self, wall_xy: np.ndarray) -> np.ndarray:
        """Texture pixels of wall points: the texture's centre on the optical axis point,
        one texture pixel per ``Zc / f`` wall units (the frontal resolution)."""
        unit = DISTANCE / self.focal
        th, tw = TEXTURE.shape[:2]
        col = (wall_xy[:, 1] - self.axis_point[1]) / unit + (tw - 1) / 2
        row = (th - 1) / 2 - (wall_xy[:, 0] - self.axis_point[0]) / unit
        return np.column_stack([col, row])

    def render(self) -> np.ndarray:
        cols, rows = np.meshgrid(np.arange(WIDTH, dtype=float), np.arange(HEIGHT, dtype=float))
        wall = self.wall_of_pixels(np.column_stack([cols.ravel(), rows.ravel()]))
        texture = np.nan_to_num(self.texture_coordinates(wall), nan=-100.0)
        map_x = texture[:, 0].reshape(HEIGHT, WIDTH).astype(np.float32)
        map_y = texture[:, 1].reshape(HEIGHT, WIDTH).astype(np.float32)
        return cv2.remap(TEXTURE, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)

    def output_wall_points(self) -> np.ndarray:
        """The wall point of every pixel of the default output frame (docs/CONVENTIONS.md)."""
        cx, cy = self.k[0, 2], self.k[1, 2]
        cols, rows = np.meshgrid(np.arange(WIDTH, dtype=float), np.arange(HEIGHT, dtype=float))
        unit = DISTANCE / self.focal
        return np.column_stack([self.axis_point[0] + (cy - rows.ravel()) * unit,
                                self.axis_point[1] + (cols.ravel() - cx) * unit])

    def reference(self, image: np.ndarray, margin: float = 2.0):
        """One ``cv2.remap`` of the camera image into the default output frame, and the
        mask of output pixels whose source lies ``margin`` inside the image."""
        sources = self.pixels_of_wall(self.output_wall_points())
        inside = np.all(np.isfinite(sources), axis=1)
        inside &= (sources[:, 0] >= margin) & (sources[:, 0] <= WIDTH - 1 - margin)
        inside &= (sources[:, 1] >= margin) & (sources[:, 1] <= HEIGHT - 1 - margin)
        sources = np.nan_to_num(sources, nan=-100.0)
        map_x = sources[:, 0].reshape(HEIGHT, WIDTH).astype(np.float32)
        map_y = sources[:, 1].reshape(HEIGHT, WIDTH).astype(np.float32)
        expected = cv2.remap(image, map_x, map_y, cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_CONSTANT)
        return expected, inside.reshape(HEIGHT, WIDTH)

    def texture_truth(self):
        """The texture itself at the output's wall points (what a perfect camera gives)."""
        texture = self.texture_coordinates(self.output_wall_points())
        return cv2.remap(TEXTURE, texture[:, 0].reshape(HEIGHT, WIDTH).astype(np.float32),
                         texture[:, 1].reshape(HEIGHT, WIDTH).astype(np.float32),
                         cv2.INTER_LINEAR)


CX, CY = (WIDTH - 1) / 2 + 3.5, (HEIGHT - 1) / 2 - 2.0
CASES = {
    "roll+25": dict(pan=20, tilt=15, roll=25, fx=260, fy=260),
    "roll-40": dict(pan=-15, tilt=25, roll=-40, fx=260, fy=260),
    "fx!=fy": dict(pan=25, tilt=-10, roll=0, fx=300, fy=240),
    "skew": dict(pan=10, tilt=20, roll=10, fx=270, fy=250, skew=12.0),
    "plumb_bob": dict(pan=20, tilt=15, roll=5, fx=240, fy=240, model="plumb_bob",
                      coefficients=dict(k1=-0.30, k2=0.08, p1=0.001, p2=-0.0015, k3=-0.01)),
    "rational": dict(pan=-20, tilt=10, roll=-8, fx=250, fy=245, model="rational_polynomial",
                     coefficients=dict(k1=0.2, k2=-0.1, p1=0.0005, p2=0.0008, k3=0.02,
                                       k4=0.45, k5=-0.05, k6=0.01)),
    "fisheye": dict(pan=15, tilt=20, roll=12, fx=170, fy=170, model="equidistant",
                    coefficients=dict(k1=0.05, k2=-0.01, k3=0.004, k4=-0.001)),
}


def camera_of(case: dict) -> OpenCVCamera:
    model = case.get("model")
    names = Lens(model).opencv_names() if model else ()
    coefficients = [case.get("coefficients", {}).get(name, 0.0) for name in names]
    return OpenCVCamera(case["pan"], case["tilt"], case["roll"], case["fx"], case["fy"], CX, CY,
                        case.get("skew", 0.0), model, coefficients)


def sidecar_row(name: str, case: dict) -> dict[str, object]:
    row = {"image": name, "pan": case["pan"], "tilt": case["tilt"], "roll": case["roll"],
           "fx": case["fx"], "fy": case["fy"], "cx": CX, "cy": CY,
           "skew": case.get("skew", 0.0)}
    if case.get("model"):
        row["distortion_model"] = case["model"]
        row.update(case["coefficients"])
    return row


@pytest.fixture(scope="module")
def rectified(tmp_path_factory):
    """Every case rendered through its OpenCV camera, then rectified by one gsrwt call."""
    folder = tmp_path_factory.mktemp("cameras")
    rows = []
    for name, case in CASES.items():
        cv2.imwrite(str(folder / f"{name}.png"), camera_of(case).render())
        rows.append(sidecar_row(f"{name}.png", case))
    columns = sorted({key for row in rows for key in row}, key=lambda k: (k != "image", k))
    lines = [",".join(columns)] + [",".join(str(row.get(c, "")) for c in columns) for row in rows]
    (folder / "views.csv").write_text("\n".join(lines) + "\n")
    result = run_gsrwt("rectify", str(folder), "--sidecar", str(folder / "views.csv"),
                       "-o", str(folder / "out"), "--no-antialias")
    assert result.returncode == 0, result.stderr
    return folder


@pytest.mark.parametrize("name", list(CASES))
def test_rectify_matches_a_one_pass_remap_through_the_opencv_camera(rectified, name):
    camera = camera_of(CASES[name])
    image = cv2.imread(str(rectified / f"{name}.png"))
    output = cv2.imread(str(rectified / "out" / f"{name}.png"))
    expected, inside = camera.reference(image)
    assert inside.mean() > 0.5, inside.mean()
    assert psnr(output, expected, inside) >= 40, psnr(output, expected, inside)
    # And the frontal view is the wall itself (up to the camera's own resampling).
    assert psnr(output, camera.texture_truth(), inside) >= 28
    # Not an accident of smooth pixels: the camera image itself is far from it.
    assert psnr(image, camera.texture_truth(), inside) < 20


def test_undistorting_first_and_warping_second_is_worse_than_one_pass(rectified):
    """The two-interpolation route that one-pass rectification replaces, measured."""
    case = CASES["plumb_bob"]
    camera = camera_of(case)
    image = cv2.imread(str(rectified / "plumb_bob.png"))
    output = cv2.imread(str(rectified / "out" / "plumb_bob.png"))
    expected, inside = camera.reference(image)
    undistorted = cv2.undistort(image, camera.k, camera.coefficients)
    view = View(case["pan"], case["tilt"], roll=case["roll"], fx=case["fx"], fy=case["fy"],
                cx=CX, cy=CY, width=WIDTH, height=HEIGHT)
    from gsrwt_cli.geometry.framing import output_from_input

    two_pass = cv2.warpPerspective(undistorted, output_from_input(view), (WIDTH, HEIGHT),
                                   flags=cv2.INTER_LINEAR)
    one_pass_db, two_pass_db = psnr(output, expected, inside), psnr(two_pass, expected, inside)
    assert one_pass_db >= two_pass_db + 5, (one_pass_db, two_pass_db)


def test_roll_zero_is_the_thesis_and_roll_turns_the_vanishing_point():
    plain = View(15, 30, 280, width=WIDTH, height=HEIGHT)
    zero = View(15, 30, 280, width=WIDTH, height=HEIGHT, roll=0.0)
    np.testing.assert_array_equal(plain.image_from_pixel(), zero.image_from_pixel())
    rolled = View(15, 30, 280, width=WIDTH, height=HEIGHT, roll=30.0)
    row, rolled_row = params_row(plain), params_row(rolled)
    for column in ("theta_deg", "a_px", "foreshortening", "delta_deg", "gamma_deg"):
        assert rolled_row[column] == pytest.approx(row[column])
    # The main vanishing point turns about the principal point by -roll in the image frame
    # (the scene turns counter-clockwise): the same distance, the angle changed by 30 degrees.
    before = np.array([row["vp_x"], row["vp_y"]])
    after = np.array([rolled_row["vp_x"], rolled_row["vp_y"]])
    assert np.linalg.norm(after) == pytest.approx(np.linalg.norm(before))
    turned = math.degrees(math.atan2(after[1], after[0]) - math.atan2(before[1], before[0]))
    assert (turned + 180) % 360 - 180 == pytest.approx(-30.0)
    # ... and the pixel it names is where the independent camera sees points far down the wall.
    camera = OpenCVCamera(15, 30, 30, 280, 280, (WIDTH - 1) / 2, (HEIGHT - 1) / 2)
    far = camera.pixels_of_wall(np.array([[0.0, -1e10]]))[0]  # far along -Y, the pan side
    vanishing_line = np.array([rolled_row["vl_a"], rolled_row["vl_b"], rolled_row["vl_c"]])
    assert abs(vanishing_line @ [*far, 1.0]) < 1e-3


def test_params_reports_roll_and_both_focal_lengths(tmp_path):
    result = run_gsrwt("params", "--pan", "10", "--tilt", "5", "--roll", "-12", "--fx", "300",
                       "--fy", "280", "--width", "320", "--height", "240", "--format", "json")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout, "json")
    assert (row["roll_deg"], row["fx_px"], row["fy_px"]) == (-12, 300, 280)
    assert row["focal_px"] == pytest.approx(math.sqrt(300 * 280))


def test_rectify_remembers_maps_of_repeated_poses(tmp_path):
    """A pan-tilt unit revisits poses: the second image of a pose reuses the first's maps,
    and gives exactly the same pixels as a fresh computation would."""
    from gsrwt_cli.geometry.pixelmap import MAP_CACHE

    case = CASES["plumb_bob"]
    camera = camera_of(case)
    image = camera.render()
    lens = Lens("plumb_bob", tuple(case["coefficients"].items()))
    view = View(case["pan"], case["tilt"], roll=case["roll"], fx=case["fx"], fy=case["fy"],
                cx=CX, cy=CY, lens=lens)
    from gsrwt_cli.api.rectify import rectify_image

    MAP_CACHE.clear()
    first, _ = rectify_image(image, view, antialias=False)
    second, _ = rectify_image(image, view, antialias=False)
    assert (MAP_CACHE.hits, MAP_CACHE.misses) == (1, 1)
    np.testing.assert_array_equal(first, second)


def test_a_bad_lens_in_a_sidecar_names_the_row_and_field(tmp_path):
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(40, 50, 1))
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal,distortion_model,k1\na.png,10,5,300,wideangle,-0.3\n")
    result = run_gsrwt("params", "--sidecar", str(tmp_path / "views.csv"))
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert "views.csv line 2, field 'distortion_model'" in line and "wideangle" in line


def test_full_frame_follows_the_distorted_border():
    """--bbox full of a barrel-distorted view covers what the lens shows, which a pinhole of
    the same K would not: its extent comes from the undistorted image border."""
    from gsrwt_cli.geometry.framing import full_frame

    lens = Lens("plumb_bob", (("k1", -0.3), ("k2", 0.08)))
    pinhole = View(10, 5, 240, width=WIDTH, height=HEIGHT)
    barrel = View(10, 5, 240, width=WIDTH, height=HEIGHT, lens=lens)
    plain, wide = full_frame(pinhole, 4.0), full_frame(barrel, 4.0)
    assert (wide.x1 - wide.x0) > 1.15 * (plain.x1 - plain.x0)
    assert (wide.y1 - wide.y0) > 1.15 * (plain.y1 - plain.y0)



def test_sidecar_poses_from_solvepnp_and_quaternions(tmp_path):
    """rvec/tvec columns (solvePnP's camera_from_wall) and quaternions give the pose that
    cv2.Rodrigues and the camera built from words agree on; a wall behind is that row's
    error."""

    from gsrwt_cli.geometry.rotations import opencv_from_world_from_camera, quaternion_from_rotation

    pan, tilt, roll = 25.0, -12.0, 8.0
    up, right, forward = camera_axes(pan, tilt, roll)
    # Rows: the camera's OpenCV axes (x right, y down, z forward) in the wall's OpenCV frame
    # (x right = world Y, y down = -world X, z into the wall = world Z).
    thesis_from_opencv = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    camera_from_wall = np.stack([right, -up, forward]) @ thesis_from_opencv
    rvec = cv2.Rodrigues(camera_from_wall)[0].ravel()
    centre_in_wall = np.array([0.3, -0.2, -4.0])  # 4 units in front of the wall plane
    tvec = -camera_from_wall @ centre_in_wall
    qw, qx, qy, qz = quaternion_from_rotation(opencv_from_world_from_camera(
        np.linalg.inv(np.stack([up, right, forward]))))
    (tmp_path / "poses.csv").write_text(
        "image,focal,rvec_x,rvec_y,rvec_z,tvec_x,tvec_y,tvec_z,qw,qx,qy,qz\n"
        f"a.png,300,{','.join(map(str, rvec))},{','.join(map(str, tvec))},,,,\n"
        f"b.png,300,,,,,,,{qw},{qx},{qy},{qz}\n")
    result = run_gsrwt("params", "--sidecar", str(tmp_path / "poses.csv"), "--format", "json")
    assert result.returncode == 0, result.stderr
    for row in read_table(result.stdout, "json"):
        assert (row["pan_deg"], row["tilt_deg"], row["roll_deg"]) == pytest.approx(
            (pan, tilt, roll), abs=1e-6), row
    (tmp_path / "behind.csv").write_text(
        f"image,focal,rvec_x,rvec_y,rvec_z\nc.png,300,0,{math.pi * 0.9},0\n")
    behind = run_gsrwt("params", "--sidecar", str(tmp_path / "behind.csv"))
    assert behind.returncode == 2
    (line,) = behind.stderr.strip().splitlines()
    assert "behind.csv line 2, field 'rvec_x'" in line and "not in front" in line


def test_the_distance_of_a_tvec_is_along_the_walls_normal():
    from gsrwt_cli.inputs.records import view_from_values

    # A camera turned left by 30 degrees, 2 units from the wall: tvec_z is 2 / cos 30.
    view = view_from_values({"rvec_x": 0, "rvec_y": math.pi / 6, "rvec_z": 0, "tvec_x": 0,
                             "tvec_y": 0, "tvec_z": 2 / math.cos(math.pi / 6), "focal": 300},
                            "hand-worked")
    assert (view.pan, view.tilt, view.roll) == pytest.approx((30, 0, 0))
    assert view.distance == pytest.approx(2.0)


def fine_texture(height: int, width: int) -> np.ndarray:
    """Detail at the pixel scale (stripes and noise): what aliases when shrunk."""
    rng = np.random.default_rng(5)
    cols, rows = np.meshgrid(np.arange(width), np.arange(height))
    stripes = 127 + 100 * np.sin(cols * 2.6 + rows * 0.9) * np.cos(rows * 2.1)
    noise = rng.normal(0, 25, (height, width))
    grey = np.clip(stripes + noise, 0, 255).astype(np.uint8)
    return cv2.merge([grey, np.roll(grey, 3, axis=1), np.roll(grey, 5, axis=0)])


def antialias_gain(image: np.ndarray, view: View, scale: float):
    """PSNR of plain bilinear and of antialiased rectification against an area-averaged
    reference: the same map applied to a 4x supersampled input, then averaged 4x4."""
    from gsrwt_cli.api.rectify import Framing, rectify_image

    plain, info = rectify_image(image, view, Framing(scale=scale), antialias=False)
    filtered, _ = rectify_image(image, view, Framing(scale=scale), antialias=True)
    fine, _ = rectify_image(image, view, Framing(scale=scale * 4), antialias=False,
                            interpolation="linear")
    height, width = plain.shape[:2]
    reference = cv2.resize(fine, (width, height), interpolation=cv2.INTER_AREA)
    valid = np.ones((height, width), bool)
    valid[:3, :] = valid[-3:, :] = valid[:, :3] = valid[:, -3:] = False
    return psnr(plain, reference, valid), psnr(filtered, reference, valid)


def test_antialiasing_where_the_output_shrinks_the_input():
    image = fine_texture(480, 640)
    frontal = View(0, 0, 500, width=640, height=480)
    plain_db, filtered_db = antialias_gain(image, frontal, 0.25)
    assert filtered_db >= plain_db + 6, (plain_db, filtered_db)
    # Pan 60 at a third of the frontal scale: the shrink runs from 1.1 to 2.1 across the
    # view, so the filter must follow it region by region.
    oblique = View(60, 0, 500, width=640, height=480)
    plain_db, filtered_db = antialias_gain(image, oblique, 0.35)
    assert filtered_db >= plain_db + 1.5, (plain_db, filtered_db)


def test_antialiasing_changes_nothing_where_nothing_shrinks():
    from gsrwt_cli.api.rectify import rectify_image

    image = fine_texture(240, 320)
    view = View(10, 5, 300)  # shrinks at most ~1.2x in the default frame
    plain, _ = rectify_image(image, view, antialias=False)
    filtered, _ = rectify_image(image, view, antialias=True)
    np.testing.assert_array_equal(plain, filtered)


def test_focal_length_in_millimetres_with_the_sensor_size(tmp_path):
    """focal_mm and sensor_width_mm (sensor_height_mm for fy) become pixels with the image's
    own size, read from the file when the row does not give it."""
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(300, 400, 3))
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal_mm,sensor_width_mm,sensor_height_mm\na.png,10,5,4.73,6.17,\n")
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), "--sidecar",
                       str(tmp_path / "views.csv"), "-o", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    (row,) = read_table(tmp_path / "out" / "gsrwt.csv")
    assert float(row["fx_px"]) == pytest.approx(4.73 * 400 / 6.17, abs=1e-5)
    assert float(row["fy_px"]) == pytest.approx(4.73 * 400 / 6.17, abs=1e-5)
    assert row["focal_source"] == "sidecar"
    both = run_gsrwt("params", "--pan", "1", "--tilt", "2", "--width", "400", "--height", "300",
                     "--sidecar", str(tmp_path / "views.csv"), "--format", "json")
    (params,) = read_table(both.stdout, "json")
    assert params["fy_px"] == pytest.approx(params["fx_px"])
    (tmp_path / "rect.csv").write_text(
        "image,pan,tilt,focal_mm,sensor_width_mm,sensor_height_mm,width,height\n"
        "a.png,10,5,4.73,6.17,4.63,400,300\n")
    skewed = run_gsrwt("params", "--sidecar", str(tmp_path / "rect.csv"), "--format", "json")
    (params,) = read_table(skewed.stdout, "json")
    assert params["fy_px"] == pytest.approx(4.73 * 300 / 4.63)


def test_max_size_lowers_the_scale_and_records_it(tmp_path):

    image = camera_of(CASES["roll+25"]).render()
    cv2.imwrite(str(tmp_path / "v.png"), image)
    common = ["rectify", str(tmp_path / "v.png"), "--pan", "20", "--tilt", "15", "--roll", "25",
              "--focal", "260", "--bbox", "full", "--table", "-"]
    fitted = run_gsrwt(*common, "--max-size", "400x300", "-o", str(tmp_path / "fit"))
    assert fitted.returncode == 0, fitted.stderr
    (row,) = read_table(fitted.stdout)
    width, height, scale = int(row["out_width"]), int(row["out_height"]), float(row["scale"])
    assert width <= 400 and height <= 300 and (width >= 399 or height >= 299)
    assert scale < 1
    again = run_gsrwt(*common, "--scale", repr(scale), "-o", str(tmp_path / "scaled"))
    assert again.returncode == 0, again.stderr
    fit, scaled = (cv2.imread(str(tmp_path / name / "v.png")) for name in ("fit", "scaled"))
    assert fit.shape == scaled.shape  # the recorded scale (6 decimals) makes the same view
    assert psnr(fit, scaled, np.ones(fit.shape[:2], bool)) > 40
    bad = run_gsrwt(*common, "--max-size", "400by300", "-o", str(tmp_path / "bad"))
    assert bad.returncode == 2 and "--max-size" in bad.stderr


@pytest.mark.parametrize("name", ["roll+25", "plumb_bob", "fisheye"])
def test_bbox_crop_is_the_largest_rectangle_without_fill(tmp_path, name):
    """--bbox crop with --alpha: not one transparent pixel, and most of what --bbox full
    shows of the image is kept (the visible wall's largest inscribed rectangle)."""

    case = CASES[name]
    cv2.imwrite(str(tmp_path / "v.png"), camera_of(case).render())
    row = sidecar_row("v.png", case)
    (tmp_path / "views.csv").write_text(",".join(row) + "\n" + ",".join(map(str, row.values()))
                                        + "\n")
    areas = {}
    for bbox in ("crop", "full"):
        result = run_gsrwt("rectify", str(tmp_path / "v.png"), "--sidecar",
                           str(tmp_path / "views.csv"), "--bbox", bbox, "--alpha", "--ext",
                           "png", "-o", str(tmp_path / bbox), "--table", "-")
        assert result.returncode == 0, result.stderr
        (table_row,) = read_table(result.stdout)
        output = cv2.imread(str(tmp_path / bbox / "v.png"), cv2.IMREAD_UNCHANGED)
        assert (output.shape[1], output.shape[0]) == (int(table_row["out_width"]),
                                                      int(table_row["out_height"]))
        areas[bbox] = int((output[..., 3] > 0).sum())
        if bbox == "crop":
            assert output[..., 3].min() == 255, "fill inside the crop"
    assert areas["crop"] > 0.4 * areas["full"], areas  # a barrel border curves inward


def test_render_through_a_lens_and_rectify_it_back():
    """gsrwt render of a distorted camera, rectified through the same lens, gives the same
    frontal view as a pinhole camera's render rectified: the lens is undone exactly once."""
    from gsrwt_cli.api.rectify import rectify_image
    from gsrwt_cli.batch.render_jobs import render_view

    lens = Lens("plumb_bob", (("k1", -0.25), ("k2", 0.05), ("p1", 0.001)))
    common = dict(roll=10, fx=250, fy=240, cx=CX, cy=CY, width=WIDTH, height=HEIGHT)
    pinhole = View(20, 15, **common)
    distorted = View(20, 15, lens=lens, **common)
    texture = smooth_texture(500, 700, 8)
    pinhole_view = render_view(texture, pinhole)
    distorted_view = render_view(texture, distorted)
    assert psnr(pinhole_view, distorted_view, np.ones((HEIGHT, WIDTH), bool)) < 20
    back_pinhole, _ = rectify_image(pinhole_view, pinhole, antialias=False, alpha=True)
    back_distorted, _ = rectify_image(distorted_view, distorted, antialias=False, alpha=True)
    seen = (back_pinhole[..., 3] == 255) & (back_distorted[..., 3] == 255)
    seen = cv2.erode(seen.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    assert seen.mean() > 0.4
    assert psnr(back_pinhole[..., :3], back_distorted[..., :3], seen) >= 35


@pytest.mark.parametrize("model, coefficients, focal", [
    ("plumb_bob", (("k1", -0.3), ("k2", 0.08), ("p1", 0.001)), 2400),
    ("rational_polynomial", (("k1", 0.2), ("k2", -0.1), ("k4", 0.45)), 2400),
    ("equidistant", (("k1", 0.05), ("k2", -0.01)), 1200),
])
def test_big_frames_lens_maps_interpolated_from_a_grid_err_under_a_hundredth_pixel(
        model, coefficients, focal):
    from gsrwt_cli.api.rectify import plan_image

    plan = plan_image(View(20, 15, focal, roll=7, lens=Lens(model, coefficients)), 2000, 1500)
    lens = plan.view.intrinsics.distortion()
    grid_x, grid_y = lens.maps(plan.homography, plan.size)
    exact_x, exact_y = lens.maps(plan.homography, plan.size, step=1)  # every pixel by OpenCV
    inside = (exact_x > 0) & (exact_x < 1999) & (exact_y > 0) & (exact_y < 1499)
    assert inside.mean() > 0.5
    assert np.hypot(grid_x - exact_x, grid_y - exact_y)[inside].max() < 0.01


def test_big_frames_maps_reuse_the_last_frames_memory_and_stay_exact():
    """Maps of frames too big to keep several of are written into the memory of the last
    frame's maps: each pose's maps are still exactly those of a fresh computation."""
    from gsrwt_cli.api.rectify import plan_image
    from gsrwt_cli.geometry.pixelmap import MAP_CACHE, _MapCache

    lens_model = Lens("plumb_bob", (("k1", -0.2), ("k2", 0.05)))
    plans = [plan_image(View(pan, 10, 1800, lens=lens_model), 1600, 1200) for pan in (15, 25)]
    sizes = {plan.size for plan in plans}
    assert len(sizes) == 1  # the same frame, so the second reuses the first's memory
    cache = _MapCache(budget=4 * plans[0].size[0] * plans[0].size[1] * 8 - 1)
    lens = plans[0].view.intrinsics.distortion()
    first = cache.get(lens, plans[0].homography, plans[0].size)
    first_copy = [part.copy() for part in first]
    second = cache.get(lens, plans[1].homography, plans[1].size)
    assert second[0].base is first[0].base  # the same memory, overwritten
    assert not np.array_equal(first_copy[0], second[0])
    fresh = lens.maps(plans[1].homography, plans[1].size)
    for part, expected in zip(second, fresh):
        np.testing.assert_array_equal(part, expected)
    assert cache.get(lens, plans[1].homography, plans[1].size) is second  # the last, again
    assert (cache.hits, cache.misses, len(cache.entries)) == (1, 2, 0)
    assert MAP_CACHE is not cache


def test_big_frames_revisited_poses_take_their_grid_from_the_cache():
    """A pan-tilt unit's cycle of poses on big frames: a pose seen before (not last) is
    expanded from its kept grid, without evaluating the lens again, into the last frame's
    memory, and its maps are exactly a fresh computation's; the grids stay within their
    budget, oldest out first."""
    from gsrwt_cli.api.rectify import plan_image
    from gsrwt_cli.geometry.pixelmap import _MapCache

    lens_model = Lens("plumb_bob", (("k1", -0.2), ("k2", 0.05)))
    plans = [plan_image(View(pan, 10, 1800, lens=lens_model), 1600, 1200)
             for pan in (15, 25, 35)]
    size = plans[0].size
    lens = plans[0].view.intrinsics.distortion()
    one_grid = 2 * 4 * (-(-size[0] // 4) + 3) * (-(-size[1] // 4) + 3)
    cache = _MapCache(budget=4 * size[0] * size[1] * 8 - 1, grid_budget=2 * one_grid)
    first = cache.get(lens, plans[0].homography, size)
    cache.get(lens, plans[1].homography, size)
    again = cache.get(lens, plans[0].homography, size)  # revisited: from its grid
    assert (cache.hits, cache.misses) == (1, 2)
    assert again[0].base is first[0].base  # the last frame's memory, reused
    for part, expected in zip(again, lens.maps(plans[0].homography, size)):
        np.testing.assert_array_equal(part, expected)
    cache.get(lens, plans[2].homography, size)  # a third pose: the oldest grid goes
    assert len(cache.grids) == 2
    cache.get(lens, plans[1].homography, size)
    assert (cache.hits, cache.misses) == (1, 4)


def test_lens_shrink_from_the_maps_matches_the_lens_projection():
    """The anti-aliasing's shrink through a lens is read off the warp's own maps; it agrees
    with finite differences of the lens projection (cv2.projectPoints) to 1 %."""
    from gsrwt_cli.api.rectify import Framing, plan_image
    from gsrwt_cli.geometry.gsrwt import largest_singular_value

    plan = plan_image(View(55, 10, 700, lens=Lens("plumb_bob", (("k1", -0.25), ("k2", 0.06)))),
                      1600, 1200, Framing(scale=0.4))
    pixel_map = plan.pixel_map
    shrink = pixel_map.shrink(32)
    width, height = plan.size
    cols = np.arange(0, width + 31, 32, dtype=np.float64).clip(max=width - 1)
    rows = np.arange(0, height + 31, 32, dtype=np.float64).clip(max=height - 1)
    grid = np.stack(np.meshgrid(cols, rows), axis=-1).reshape(-1, 2)
    lens = plan.view.intrinsics.distortion()
    ideal = cv2.perspectiveTransform(grid[None], np.linalg.inv(plan.homography))[0]
    here = lens.distort(ideal)
    right = lens.distort(cv2.perspectiveTransform(
        (grid + [0.01, 0])[None], np.linalg.inv(plan.homography))[0])
    down = lens.distort(cv2.perspectiveTransform(
        (grid + [0, 0.01])[None], np.linalg.inv(plan.homography))[0])
    a, c = ((right - here) / 0.01).T
    b, d = ((down - here) / 0.01).T
    expected = largest_singular_value(a, b, c, d).reshape(shrink.shape)
    assert expected.max() > 1.5  # the case shrinks enough to be anti-aliased
    np.testing.assert_allclose(shrink, expected, rtol=0.01)


# --------------------------------------------------------------------------------------------
# Lenses whose model folds back: beyond the radius where the distorted radius stops growing,
# like beyond the horizon, nothing is sampled or framed.
# --------------------------------------------------------------------------------------------

MAGENTA = np.array([255, 0, 255], np.uint8)
FOLD_CASES = {
    "k1=-5": dict(pan=20, tilt=15, roll=5, fx=400, fy=400, model="plumb_bob",
                  coefficients=dict(k1=-5.0)),
    "k1=-1": dict(pan=-20, tilt=15, roll=0, fx=240, fy=240, model="plumb_bob",
                  coefficients=dict(k1=-1.0)),
    "fisheye k1=-1": dict(pan=15, tilt=20, roll=12, fx=170, fy=170, model="equidistant",
                          coefficients=dict(k1=-1.0)),
    "rational k4=2": dict(pan=-20, tilt=10, roll=-8, fx=160, fy=155,
                          model="rational_polynomial", coefficients=dict(k1=0.1, k4=2.0)),
}


def fold_of(camera: OpenCVCamera) -> tuple[float, float]:
    """The normalized ideal radius where the distorted radius first stops growing, and the
    largest distorted radius, found with OpenCV's own projection of rays along a line out of
    the axis (inf, inf if it never stops, up to 89.9 degrees off axis)."""
    radii = np.tan(np.linspace(0, math.radians(89.9), 200_001))
    rays = np.column_stack([radii, np.zeros_like(radii), np.ones_like(radii)])[:, None, :]
    zero = np.zeros(3)
    if camera.model == "equidistant":
        distorted, _ = cv2.fisheye.projectPoints(rays, zero, zero, np.eye(3),
                                                 camera.coefficients)
    else:
        distorted, _ = cv2.projectPoints(rays, zero, zero, np.eye(3), camera.coefficients)
    along = distorted.reshape(-1, 2)[:, 0]
    stops = np.nonzero(np.diff(along) <= 0)[0]
    if len(stops) == 0:
        return math.inf, math.inf
    return float(radii[stops[0]]), float(along[stops[0]])


def fold_radius(camera: OpenCVCamera) -> float:
    return fold_of(camera)[0]


def render_with_no_ray_in_magenta(camera: OpenCVCamera) -> np.ndarray:
    """The camera's image, with magenta at the pixels no ray reaches: those further from the
    principal point (normalized) than the largest distorted radius."""
    image = camera.render()
    cols, rows = np.meshgrid(np.arange(WIDTH, dtype=float), np.arange(HEIGHT, dtype=float))
    normalized = np.column_stack([cols.ravel(), rows.ravel(), np.ones(WIDTH * HEIGHT)]
                                 ) @ np.linalg.inv(camera.k).T
    unreached = np.hypot(normalized[:, 0], normalized[:, 1]) > fold_of(camera)[1]
    image.reshape(-1, 3)[unreached] = MAGENTA
    return image


def output_ray_radius(camera: OpenCVCamera) -> np.ndarray:
    """The normalized radius of the ray each default-frame output pixel looks along (inf
    where the ray looks away from the wall), from the camera built from words."""
    world = np.column_stack([camera.output_wall_points(), np.full(WIDTH * HEIGHT, DISTANCE)])
    rays = world @ camera.camera_from_world.T
    with np.errstate(divide="ignore", invalid="ignore"):
        radius = np.where(rays[:, 2] > 0, np.hypot(rays[:, 0], rays[:, 1]) / rays[:, 2],
                          np.inf)
    return radius.reshape(HEIGHT, WIDTH)


@pytest.fixture(scope="module")
def folded(tmp_path_factory):
    """Every folding case rendered through its OpenCV camera (magenta where no ray reaches),
    then rectified by one gsrwt call with --alpha."""
    folder = tmp_path_factory.mktemp("folding")
    rows = []
    for index, case in enumerate(FOLD_CASES.values()):
        camera = camera_of(case)
        image = render_with_no_ray_in_magenta(camera)
        cv2.imwrite(str(folder / f"{index}.png"), image)
        rows.append(sidecar_row(f"{index}.png", case))
    columns = sorted({key for row in rows for key in row}, key=lambda k: (k != "image", k))
    lines = [",".join(columns)] + [",".join(str(row.get(c, "")) for c in columns) for row in rows]
    (folder / "views.csv").write_text("\n".join(lines) + "\n")
    result = run_gsrwt("rectify", str(folder), "--sidecar", str(folder / "views.csv"),
                       "-o", str(folder / "out"), "--no-antialias", "--alpha")
    assert result.returncode == 0, result.stderr
    return folder


@pytest.mark.parametrize("index, name", list(enumerate(FOLD_CASES)))
def test_nothing_beyond_a_folding_lens_radius_is_sampled(folded, index, name):
    """Output pixels whose ray lies beyond the fold radius are transparent fill, never the
    mirrored picture; those within it and inside the image are the picture, as OpenCV's own
    camera projects it; and no output pixel is the magenta of pixels no ray reaches."""
    camera = camera_of(FOLD_CASES[name])
    fold = fold_radius(camera)
    assert math.isfinite(fold)
    image = cv2.imread(str(folded / f"{index}.png"))
    output = cv2.imread(str(folded / "out" / f"{index}.png"), cv2.IMREAD_UNCHANGED)
    seen = output[..., 3] == 255
    radius = output_ray_radius(camera)
    beyond = radius > fold * 1.005
    expected, inside = camera.reference(image)
    within = inside & (radius < fold * 0.995)
    assert beyond.mean() > 0.05 and within.mean() > 0.05, (beyond.mean(), within.mean())
    assert not seen[beyond].any(), f"{int(seen[beyond].sum())} pixels beyond the fold sampled"
    assert seen[within].all()
    assert not np.all(output[..., :3] == MAGENTA, axis=2)[seen].any()
    well_inside = within & (radius < fold * 0.9)
    assert psnr(output[..., :3], expected, well_inside) >= 35


def test_a_view_wholly_beyond_the_fold_is_refused_with_the_reason(tmp_path):
    """A frame that sees only rays beyond the fold radius is that image's error row (exit 1),
    one line naming the fold; the batch's other image is rectified. The box is the image's
    top-left corner, 163 to 200 pixels from the principal point: beyond a's fold, within b's
    image."""
    cv2.imwrite(str(tmp_path / "a.png"), smooth_texture(HEIGHT, WIDTH, 3))
    cv2.imwrite(str(tmp_path / "b.png"), smooth_texture(HEIGHT, WIDTH, 4))
    (tmp_path / "views.csv").write_text(
        "image,pan,tilt,focal,distortion_model,k1\n"
        "a.png,0,0,600,plumb_bob,-5\n"  # folds 14.5 degrees (155 px) off axis
        "b.png,0,0,600,plumb_bob,-0.1\n")
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), str(tmp_path / "b.png"),
                       "--sidecar", str(tmp_path / "views.csv"), "--bbox", "0,0,30,20",
                       "-o", str(tmp_path / "out"), "--table", "-")
    assert result.returncode == 1
    (line,) = [line for line in result.stderr.splitlines() if line.startswith("Error")]
    assert "a.png" in line and "lens model folds back 14.5 degrees off axis" in line
    assert "155 pixels" in line
    assert not (tmp_path / "out" / "a.png").exists()
    corner = cv2.imread(str(tmp_path / "out" / "b.png"))
    assert corner is not None and corner.std() > 0  # b's own pixels, not fill
    result = run_gsrwt("rectify", str(tmp_path / "a.png"), "--sidecar",
                       str(tmp_path / "views.csv"), "--bbox", "full", "-o", str(tmp_path / "full"))
    assert result.returncode == 0, result.stderr  # the whole image does see within it


@pytest.mark.parametrize("model, coefficients", [
    ("plumb_bob", [50.0, 0, 0, 0, 0]),
    ("equidistant", [10.0, 0, 0, 0]),
    ("plumb_bob", [-5.0, 0, 0, 0, 0]),
    ("equidistant", [-1.0, 0, 0, 0]),
    ("rational_polynomial", [0.1, 0, 0, 0, 0, 2.0, 0, 0]),
])
def test_the_inverse_of_a_strong_lens_is_its_monotonic_part(model, coefficients):
    """Pixels of rays within the fold radius (any ray for a lens that never folds), put on
    the image by OpenCV's projection, come back to their rays (where OpenCV's own fisheye
    inverse stops at 90 degrees of distorted angle); pixels beyond any ray's reach have no
    ideal pixel (NaN), and the lens never maps a ray beyond the fold."""

    focal = 200.0
    lens = View(0, 0, focal, width=WIDTH, height=HEIGHT,
                lens=Lens(model, tuple(zip(Lens(model).opencv_names(), coefficients)))
                ).intrinsics.distortion()
    camera = OpenCVCamera(0, 0, 0, focal, focal, (WIDTH - 1) / 2, (HEIGHT - 1) / 2,
                          model=model, coefficients=coefficients)
    fold = min(fold_radius(camera), math.tan(math.radians(80)))
    rng = np.random.default_rng(5)
    radius = rng.uniform(0, fold * 0.995, 2000)
    angle = rng.uniform(0, 2 * math.pi, 2000)
    rays = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), np.ones(2000)])
    zero = np.zeros(3)
    if model == "equidistant":
        pixels, _ = cv2.fisheye.projectPoints(rays[:, None, :], zero, zero, camera.k,
                                              camera.coefficients)
    else:
        pixels, _ = cv2.projectPoints(rays, zero, zero, camera.k, camera.coefficients)
    pixels = pixels.reshape(-1, 2)
    ideal = rays[:, :2] * focal + camera.k[:2, 2]
    back = lens.undistort(pixels)
    # Near the fold the inverse is ill-conditioned (d r_d / d r -> 0): there the ray must
    # project back onto its pixel; further in it must be the ray itself.
    again, _ = cv2.projectPoints(np.column_stack([(back - camera.k[:2, 2]) / focal,
                                                  np.ones(2000)]), zero, zero, camera.k,
                                 camera.coefficients) if model != "equidistant" else (
        cv2.fisheye.projectPoints(np.column_stack([(back - camera.k[:2, 2]) / focal,
                                                   np.ones(2000)])[:, None, :], zero, zero,
                                  camera.k, camera.coefficients))
    assert np.hypot(*(again.reshape(-1, 2) - pixels).T).max() < 0.01
    assert (np.hypot(*((back - camera.k[:2, 2]) / focal).T) < fold * 1.0001).all()
    conditioned = radius < 0.95 * fold
    assert np.hypot(*(back - ideal)[conditioned].T).max() < 0.01
    beyond = ideal + (ideal - camera.k[:2, 2]) * (fold * 1.2 / np.maximum(radius, 1e-9) - 1
                                                  )[:, None]
    if math.isfinite(fold_radius(camera)):
        assert np.isnan(lens.distort(beyond)).all()
        far = camera.k[:2, 2] + 5000 * np.column_stack([np.cos(angle), np.sin(angle)])
        assert np.isnan(lens.undistort(far)).all()  # past the largest distorted radius
