"""Images in object storage: ``s3://`` in and out, against a real local S3 server.

The server is moto's ``ThreadedMotoServer``, started by this module on a loopback port;
every S3 call names it (``AWS_ENDPOINT_URL`` in the environment of every ``gsrwt`` process
and of the Dask workers, before they import fsspec; ``endpoint_url`` in this process), with
dummy credentials, so nothing ever tries a public host. Runs are real ``gsrwt`` subprocesses
and, for the cluster, real ``dask.distributed.LocalCluster`` processes.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.helpers.cli import GSRWT, run_gsrwt, start_gsrwt
from tests.helpers.faults import POSE, assert_clean_stderr, make_photos
from tests.helpers.paths import DATA, ROOT
from tests.helpers.tables import read_table

# Skipped only where the test extra is not installed; CI installs it and must run them.
_need = __import__("importlib").import_module if os.environ.get("CI") else pytest.importorskip
_need("s3fs")
moto_server = _need("moto.server")
distributed = _need("distributed")

from gsrwt_cli.io.outputs import OutsideOutputError, check_inside, open_atomic  # noqa: E402
from gsrwt_cli.io.storage import Location, is_url, list_files, location  # noqa: E402

SAMPLES = ROOT / "sample_data" / "views"


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.fixture(scope="module")
def s3(tmp_path_factory):
    """A local S3 server and the environment that points every process at it only."""
    port = free_port()
    server = moto_server.ThreadedMotoServer(ip_address="127.0.0.1", port=port, verbose=False)
    server.start()
    endpoint = f"http://127.0.0.1:{port}"
    environment = {
        "AWS_ENDPOINT_URL": endpoint, "AWS_ENDPOINT_URL_S3": endpoint,
        "FSSPEC_S3_ENDPOINT_URL": endpoint, "AWS_ACCESS_KEY_ID": "testing",
        "AWS_SECRET_ACCESS_KEY": "testing", "AWS_DEFAULT_REGION": "eu-west-1",
        "AWS_EC2_METADATA_DISABLED": "true", "DASK_SCHEDULER_ADDRESS": "",
    }
    import s3fs

    fs = s3fs.S3FileSystem(endpoint_url=endpoint, key="testing", secret="testing",
                           client_kwargs={"region_name": "eu-west-1"},
                           use_listings_cache=False, skip_instance_cache=True)
    try:
        yield fs, environment
    finally:
        server.stop()


def upload(fs, folder: Path, prefix: str) -> None:
    for path in sorted(folder.rglob("*")):
        if path.is_file():
            fs.pipe_file(f"{prefix}/{path.relative_to(folder).as_posix()}", path.read_bytes())


def objects(fs, prefix: str) -> dict[str, bytes]:
    """Relative key -> bytes of every object below ``prefix``."""
    return {name[len(prefix) + 1:]: fs.cat_file(name) for name in fs.find(prefix)}


def local_files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*")
            if p.is_file()}


@pytest.fixture(scope="module")
def mixed(tmp_path_factory) -> Path:
    """Sample views, two calibrated chessboard photos (a ``camera`` file beside the
    sidecar), and images that fail: undecodable, truncated, without parameters."""
    folder = tmp_path_factory.mktemp("mixed")
    for path in SAMPLES.glob("*.jpg"):
        shutil.copy(path, folder / path.name)
    (folder / "sub").mkdir()
    shutil.copy(SAMPLES / "corridor_p30_t30.png", folder / "sub" / "c.png")
    rows = read_table(SAMPLES / "views.csv")
    wanted = {p.name for p in folder.glob("*.jpg")}
    fields = ["image", "pan", "tilt", "focal", "camera", "rvec_x", "rvec_y", "rvec_z"]
    lines = [",".join(fields)]
    for row in rows:
        if row["image"] in wanted:
            lines.append(f"{row['image']},{row['pan']},{row['tilt']},{row['focal']},,,,")
        if row["image"] == "corridor_p30_t30.png":
            lines.append(f"sub/c.png,{row['pan']},{row['tilt']},{row['focal']},,,,")
    poses = read_table(DATA / "right_poses.csv")
    for pose in poses[:2]:
        shutil.copy(DATA / pose["image"], folder / pose["image"])
        lines.append(f"{pose['image']},,,,cal/right_camera.yml,{pose['rvec_x']},"
                     f"{pose['rvec_y']},{pose['rvec_z']}")
    (folder / "cal").mkdir()
    shutil.copy(DATA / "right_camera.yml", folder / "cal" / "right_camera.yml")
    (folder / "views.csv").write_text("\n".join(lines) + "\n")
    (folder / "broken.jpg").write_bytes(b"not an image")
    door = (SAMPLES / "door_p20_t-8_f800.jpg").read_bytes()
    (folder / "door_cut.jpg").write_bytes(door[: len(door) // 2])
    shutil.copy(SAMPLES / "door_p40_t-12_f700.jpg", folder / "unlisted.jpg")
    return folder


def as_local(text: str, bucket_prefix: str, local_input: Path) -> str:
    """A table or message of an S3 run in the words of the local run."""
    return text.replace(f"s3://{bucket_prefix}/in/", f"{local_input}/").replace(
        f"s3://{bucket_prefix}/out/", "out/")


@pytest.mark.slow
def test_s3_to_s3_on_a_cluster_is_the_local_run(s3, mixed, tmp_path):
    fs, environment = s3
    fs.mkdir("run1")
    upload(fs, mixed, "run1/in")
    local = run_gsrwt("rectify", str(mixed), "-r", "--sidecar", str(mixed / "views.csv"), "-o",
                      "out", "-q", "-j", "2", cwd=tmp_path, env=environment)
    remote = run_gsrwt("rectify", "s3://run1/in/", "-r", "--sidecar", "s3://run1/in/views.csv",
                       "-o", "s3://run1/out/", "-q", "--scheduler", "local", "-j", "2",
                       cwd=tmp_path, env=environment)
    assert (local.returncode, remote.returncode) == (1, 1), remote.stderr
    assert as_local(remote.stderr, "run1", mixed) == local.stderr  # the same error lines
    assert local.stderr.count("Error: ") == 3
    stored = objects(fs, "run1/out")
    table = stored.pop("gsrwt.csv").decode()
    written = local_files(tmp_path / "out")
    assert as_local(table, "run1", mixed) == written.pop("gsrwt.csv").decode()
    assert stored == written  # byte for byte, the calibrated photos and sub/ included
    assert {"right01.jpg", "right02.jpg", "sub/c.png"} <= set(stored)
    statuses = [row["status"] for row in read_table(table)]
    assert statuses.count("ok") == len(stored) and statuses.count("error") == 3

    again = run_gsrwt("rectify", "s3://run1/in/", "-r", "--sidecar", "s3://run1/in/views.csv", "-o",
                      "s3://run1/out/", cwd=tmp_path, env=environment)
    assert again.returncode == 1
    assert f"0 ok, {len(stored)} skipped, 3 failed" in again.stderr
    rerun_table = fs.cat_file("run1/out/gsrwt.csv").decode()
    assert rerun_table == table.replace(",ok,", ",skipped,")  # the record carried over
    assert objects(fs, "run1/out").keys() == {*stored, "gsrwt.csv"}


@pytest.mark.slow
def test_a_worker_killed_mid_batch_on_s3_loses_nothing(s3, tmp_path, monkeypatch):
    fs, environment = s3
    for name, value in environment.items():  # the workers read the store directly
        monkeypatch.setenv(name, value)
    sources = make_photos(tmp_path / "in", 24)
    fs.mkdir("kill")
    upload(fs, tmp_path / "in", "kill/in")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None, host="127.0.0.1") as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        args = ["rectify", "s3://kill/in/", *POSE, "-o", "s3://kill/out/", "--scheduler",
                cluster.scheduler_address]
        process = start_gsrwt(*args, cwd=tmp_path, env=environment)
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and process.poll() is None:
            if len(fs.find("kill/out")) >= 2:
                break
            time.sleep(0.05)
        victim = next(iter(client.run(os.getpid).values()))
        os.kill(victim, signal.SIGKILL)
        stdout, stderr = process.communicate(timeout=180)
        assert process.returncode == 0, stderr
        assert_clean_stderr(stderr)
        assert "24 ok, 0 skipped, 0 failed" in stderr
        stored = objects(fs, "kill/out")
        rows = read_table(stored.pop("gsrwt.csv").decode())
        assert [row["image"] for row in rows] == [f"s3://kill/in/{p.name}" for p in sources]
        assert sorted(stored) == sorted(p.name for p in sources)  # nothing else, no partials
        for row in rows:
            image = cv2.imdecode(np.frombuffer(stored[row["output"].rsplit("/", 1)[1]],
                                               np.uint8), cv2.IMREAD_UNCHANGED)
            assert image is not None and image.shape[1] == int(row["out_width"])
            assert image.shape[0] == int(row["out_height"]) and row["status"] == "ok"
        client.wait_for_workers(2, timeout=60)
        rerun = run_gsrwt(*args, cwd=tmp_path, env=environment)
    assert rerun.returncode == 0 and "0 ok, 24 skipped, 0 failed" in rerun.stderr, rerun.stderr


@pytest.mark.slow
def test_shards_on_s3_add_up_to_the_whole(s3, mixed, tmp_path):
    fs, environment = s3
    fs.mkdir("shards")
    upload(fs, mixed, "shards/in")
    whole = run_gsrwt("rectify", "s3://shards/in/", "--sidecar", "s3://shards/in/views.csv", "-o",
                      "s3://shards/whole/", "-q", cwd=tmp_path, env=environment)
    for k in (1, 2):
        run_gsrwt("rectify", "s3://shards/in/", "--sidecar", "s3://shards/in/views.csv", "-o",
                  "s3://shards/out/", "-q", "--shard", f"{k}/2", cwd=tmp_path, env=environment)
    merged = run_gsrwt("tables", "merge", "s3://shards/out/gsrwt.2-of-2.csv",
                       "s3://shards/out/gsrwt.1-of-2.csv", "-o", "s3://shards/out/gsrwt.csv",
                       cwd=tmp_path, env=environment)
    assert whole.returncode == 1 and merged.returncode == 0, merged.stderr
    sharded = objects(fs, "shards/out")
    for k in (1, 2):
        sharded.pop(f"gsrwt.{k}-of-2.csv")
    table = sharded.pop("gsrwt.csv").decode().replace("s3://shards/out/", "s3://shards/whole/")
    complete = objects(fs, "shards/whole")
    assert table == complete.pop("gsrwt.csv").decode()
    assert sharded == complete


@pytest.mark.slow
def test_an_output_prefix_over_an_input_is_refused(s3, tmp_path):
    fs, environment = s3
    fs.mkdir("safe")
    fs.pipe_file("safe/in/door.jpg", (SAMPLES / "door_p8_t-2_f1500.jpg").read_bytes())
    fs.pipe_file("safe/in/views.csv", b"image,pan,tilt,focal\ndoor.jpg,8,-2,1500\n")
    result = run_gsrwt("rectify", "s3://safe/in/door.jpg", *POSE, "-o", "s3://safe/in",
                       cwd=tmp_path, env=environment)
    assert result.returncode == 2
    assert result.stderr.strip() == (
        "Error: -o s3://safe/in: output s3://safe/in/door.jpg would overwrite the input "
        "s3://safe/in/door.jpg; choose another output directory")
    recursive = run_gsrwt("rectify", "s3://safe/in/", "-r", *POSE, "-o", "s3://safe/in/out",
                          cwd=tmp_path, env=environment)
    assert recursive.returncode == 2 and "is inside the input directory" in recursive.stderr
    table = run_gsrwt("rectify", "s3://safe/in/", "--sidecar", "s3://safe/in/views.csv", "-o",
                      "s3://safe/o", "--table", "s3://safe/in/views.csv", cwd=tmp_path,
                      env=environment)
    assert table.returncode == 2
    assert table.stderr.strip() == ("Error: --table s3://safe/in/views.csv: would overwrite "
                                    "an input; choose another path")
    missing = run_gsrwt("rectify", "s3://safe/nothing/", *POSE, "-o", "s3://safe/o", cwd=tmp_path,
                        env=environment)
    assert missing.returncode == 2
    assert missing.stderr.strip() == "Error: s3://safe/nothing/: no such file or directory"
    assert fs.find("safe") == ["safe/in/door.jpg", "safe/in/views.csv"]  # nothing written


def test_a_table_and_outputs_on_s3_from_local_inputs(s3, tmp_path):
    fs, environment = s3
    fs.mkdir("mixedio")
    result = run_gsrwt("rectify", str(SAMPLES / "door_p8_t-2_f1500.jpg"), *POSE, "-o",
                       "s3://mixedio/o", "--table", "s3://mixedio/t/run.jsonl", cwd=tmp_path,
                       env=environment)
    assert result.returncode == 0, result.stderr
    local = run_gsrwt("rectify", str(SAMPLES / "door_p8_t-2_f1500.jpg"), *POSE, "-o", "o",
                      cwd=tmp_path, env=environment)
    assert local.returncode == 0
    assert fs.cat_file("mixedio/o/door_p8_t-2_f1500.jpg") == (
        tmp_path / "o" / "door_p8_t-2_f1500.jpg").read_bytes()
    (row,) = [line for line in fs.cat_file("mixedio/t/run.jsonl").decode().splitlines()]
    assert '"status": "ok"' in row and '"output": "s3://mixedio/o/door_p8_t-2_f1500.jpg"' in row


# --------------------------------------------------------------------------------------------
# A store that cannot be used: one line, exit 2, before any work
# --------------------------------------------------------------------------------------------

DOOR_POSE = ("--pan", "8", "--tilt", "-2", "--focal", "1500")


def closed_endpoint() -> dict[str, str]:
    """The environment of an S3 endpoint nobody listens on (a loopback port just freed)."""
    endpoint = f"http://127.0.0.1:{free_port()}"
    return {"AWS_ENDPOINT_URL": endpoint, "AWS_ENDPOINT_URL_S3": endpoint,
            "FSSPEC_S3_ENDPOINT_URL": endpoint}


#: name -> (the environment's changes, the arguments, what the one line must say). Each
#: run also has local images it would rectify into ``o`` if it got that far.
STORE_FAULTS = {
    "output-in-no-bucket": ({}, ["s3://faults/in/", *DOOR_POSE, "-o",
                                 "s3://no-such-bucket/out/"],
                            "-o s3://no-such-bucket/out: cannot write there (The specified "
                            "bucket does not exist)"),
    "table-in-no-bucket": ({}, ["s3://faults/in/", *DOOR_POSE, "-o", "o", "--table",
                                "s3://no-such-bucket/t.csv"],
                           "--table s3://no-such-bucket/t.csv: cannot write there (The "
                           "specified bucket does not exist)"),
    "input-unreachable": ("closed", ["s3://faults/in/", *DOOR_POSE, "-o", "o"],
                          "s3://faults/in/: cannot read (Could not connect to the endpoint"),
    "sidecar-unreachable": ("closed", [str(SAMPLES / "door_p8_t-2_f1500.jpg"), "--sidecar",
                                       "s3://faults/views.csv", "-o", "o"],
                            "s3://faults/views.csv: cannot read (Could not connect to the "
                            "endpoint"),
    "input-missing-profile": ({"AWS_PROFILE": "no-such-profile"},
                              ["s3://faults/in/", *DOOR_POSE, "-o", "o"],
                              "s3://faults/in/: cannot read (The config profile "
                              "(no-such-profile) could not be found)"),
    "sidecar-missing-profile": ({"AWS_PROFILE": "no-such-profile"},
                                [str(SAMPLES / "door_p8_t-2_f1500.jpg"), "--sidecar",
                                 "s3://faults/views.csv", "-o", "o"],
                                "s3://faults/views.csv: cannot read (The config profile "
                                "(no-such-profile) could not be found)"),
}


@pytest.fixture(scope="module")
def fault_bucket(s3):
    fs, _ = s3
    fs.mkdir("faults")
    for name in ("door_p8_t-2_f1500.jpg", "door_p20_t-8_f800.jpg"):
        fs.pipe_file(f"faults/in/{name}", (SAMPLES / name).read_bytes())
    fs.pipe_file("faults/views.csv", (SAMPLES / "views.csv").read_bytes())
    return fs


@pytest.mark.parametrize("case", sorted(STORE_FAULTS))
def test_a_store_that_cannot_be_used_is_one_line_exit_2_before_any_work(
        s3, fault_bucket, tmp_path, case):
    """A missing bucket under -o or --table, an endpoint nobody answers, a profile that
    does not exist: for inputs, sidecars and outputs, one line naming the URL and the
    store's reason, exit 2, no image decoded or written, nothing in the store changed."""
    _, environment = s3
    changes, args, expected = STORE_FAULTS[case]
    changes = closed_endpoint() if changes == "closed" else changes
    before = fault_bucket.find("faults")
    result = run_gsrwt("rectify", *args, cwd=tmp_path, env={**environment, **changes})
    assert result.returncode == 2, result.stderr
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: {expected}"), line
    assert "internal error" not in line
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    assert fault_bucket.find("faults") == before


def test_every_command_takes_urls_for_what_it_reads(s3, fault_bucket, tmp_path):
    """params, estimate, lines, match and render read their files from URLs as rectify
    does (never a local ``s3:/...``); the options that write local files refuse a URL in
    one line."""
    _, environment = s3
    fault_bucket.pipe_file("faults/knob.png", (ROOT / "sample_data" / "templates" /
                                               "knob.png").read_bytes())
    fault_bucket.pipe_file("faults/door.csv", b"image,pan,tilt,focal\n"
                           b"door_p20_t-8_f800.jpg,20,-8,800\n")
    door = "s3://faults/in/door_p20_t-8_f800.jpg"
    params = run_gsrwt("params", "--sidecar", "s3://faults/door.csv", cwd=tmp_path, env=environment)
    assert params.returncode == 0, params.stderr
    assert read_table(params.stdout)[0]["theta_deg"] != ""
    estimate = run_gsrwt("estimate", "s3://faults/in/", "--sidecar", "s3://faults/views.csv", "-o",
                         "poses.csv", cwd=tmp_path, env=environment)
    assert estimate.returncode == 0, estimate.stderr
    assert [row["image"] for row in read_table((tmp_path / "poses.csv").read_text())] == [
        "door_p20_t-8_f800.jpg", "door_p8_t-2_f1500.jpg"]  # sidecar rows: relative names
    lines = run_gsrwt("lines", "s3://faults/in/", "--sidecar", "s3://faults/door.csv", "-f", "csv",
                      cwd=tmp_path, env=environment)
    assert lines.returncode == 0, lines.stderr
    assert {row["image"] for row in read_table(lines.stdout)} == {  # one not in the sidecar
        door, "s3://faults/in/door_p8_t-2_f1500.jpg"}            # is taken as frontal
    match = run_gsrwt("match", door, "--template", "s3://faults/knob.png", "--sidecar",
                      "s3://faults/door.csv", "-f", "csv", cwd=tmp_path, env=environment)
    assert match.returncode == 0, match.stderr
    assert read_table(match.stdout)[0]["template"] == "knob.png"
    render = run_gsrwt("render", "s3://faults/knob.png", *DOOR_POSE, "-o", "r.png", cwd=tmp_path,
                       env=environment)
    assert render.returncode == 0, render.stderr
    assert (tmp_path / "r.png").is_file()
    for args in (["lines", door, "--draw", "s3://faults/drawn"],
                 ["estimate", door, "--focal", "800", "--draw", "s3://faults/drawn"],
                 ["render", "s3://faults/knob.png", *DOOR_POSE, "-o", "s3://faults/r.png"]):
        refused = run_gsrwt(*args, cwd=tmp_path, env=environment)
        assert refused.returncode == 2, refused.stderr
        (line,) = refused.stderr.splitlines()
        assert "is a URL;" in line and "takes a local path" in line, line
    assert not (tmp_path / "s3:").exists()


def test_without_fsspec_every_url_is_one_line_with_the_install_hint(tmp_path):
    """fsspec made unimportable for real (a package on PYTHONPATH whose import fails): a
    URL anywhere is one line saying how to install it, exit 2; local runs still work."""
    blocker = tmp_path / "blocker" / "fsspec"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text(
        "raise ModuleNotFoundError(\"No module named 'fsspec'\", name='fsspec')\n")
    environment = {"PYTHONPATH": str(blocker.parent)}
    door = str(SAMPLES / "door_p8_t-2_f1500.jpg")
    for args in (["rectify", door, *DOOR_POSE, "-o", "memory://out/"],
                 ["rectify", door, *DOOR_POSE, "-o", "o", "--table", "memory://t.csv"],
                 ["rectify", "s3://b/in/", *DOOR_POSE, "-o", "o"],
                 ["estimate", "s3://b/in/x.jpg"],
                 ["params", "--sidecar", "s3://b/v.csv"],
                 ["lines", "s3://b/in/x.jpg"],
                 ["tables", "merge", "memory://a.csv", "-o", "m.csv"]):
        result = run_gsrwt(*args, cwd=tmp_path, env=environment)
        assert result.returncode == 2, (args, result.stderr)
        (line,) = result.stderr.splitlines()
        assert line.startswith("Error: ") and "internal error" not in line, line
        assert line.endswith("install it with pip install 'gsrwt[dask]')"), line
    assert not (tmp_path / "o").exists() or not any((tmp_path / "o").iterdir())
    local = run_gsrwt("rectify", door, *DOOR_POSE, "-o", "o", cwd=tmp_path, env=environment)
    assert local.returncode == 0, local.stderr


# --------------------------------------------------------------------------------------------
# The storage layer itself, on fsspec's in-memory file system
# --------------------------------------------------------------------------------------------


def test_locations_name_like_paths_and_list_once():
    import fsspec

    memory = fsspec.filesystem("memory")
    for key in ("lst/run/a.jpg", "lst/run/b.yaml", "lst/run/sub/c.png", "lst/run/.hid/d.jpg",
                "lst/run/.e.jpg"):
        memory.pipe_file(key, b"x")
    prefix = Location("memory://lst/run/")
    assert str(prefix) == "memory://lst/run" and prefix.name == "run"
    image = prefix / "sub/c.png"
    assert (image.suffix, image.stem, str(image.parent)) == (".png", "c", "memory://lst/run/sub")
    assert str(image.with_suffix(".yaml")) == "memory://lst/run/sub/c.yaml"
    assert [(str(item), str(relative)) for item, relative in list_files(prefix, True)] == [
        ("memory://lst/run/a.jpg", "a.jpg"), ("memory://lst/run/b.yaml", "b.yaml"),
        ("memory://lst/run/sub/c.png", "sub/c.png")]
    assert [str(r) for _, r in list_files(prefix, False)] == ["a.jpg", "b.yaml"]
    assert prefix.list_objects() == {f"memory://lst/run/{k}" for k in (
        "a.jpg", "b.yaml", "sub/c.png", ".hid/d.jpg", ".e.jpg")}
    assert (prefix / "b.yaml").is_file() and not (prefix / "b.yml").is_file()
    assert location("file:///tmp/x.jpg") == Path("/tmp/x.jpg") and not is_url("/tmp/x")
    with pytest.raises(TypeError):
        os.fspath(prefix / "a.jpg")  # a URL never opens a local file by mistake


def test_whole_writes_on_a_store_appear_whole_or_not_at_all():
    import fsspec

    memory = fsspec.filesystem("memory")
    root = Location("memory://w/out")
    with open_atomic(root / "t.csv", "w", root=root, newline="", encoding="utf-8") as stream:
        stream.write("a,b\n")
        assert not memory.exists("/w/out/t.csv")  # nothing until the block ends
    assert memory.cat_file("/w/out/t.csv") == b"a,b\n"
    with pytest.raises(RuntimeError), open_atomic(root / "u.jpg", root=root) as stream:
        stream.write(b"half")
        raise RuntimeError("the encoder failed")
    assert not memory.exists("/w/out/u.jpg")
    with pytest.raises(OutsideOutputError):
        check_inside(root, Location("memory://w/outside/x.jpg"))
    with pytest.raises(OutsideOutputError):
        check_inside(root, Location("memory://w/out-b/x.jpg"))
    check_inside(root, root / "deep/er/x.jpg")


def test_a_local_run_does_not_import_fsspec_or_dask(tmp_path):
    probe = ("import sys; from gsrwt_cli.cli import run; sys.argv = ['gsrwt', 'rectify', "
             f"{str(SAMPLES / 'door_p8_t-2_f1500.jpg')!r}, '--pan', '8', '--tilt', '-2', "
             "'--focal', '1500', '-o', 'o', '-q', '-j', '1']\n"
             "try:\n    run()\nexcept SystemExit:\n    pass\n"
             "print(sorted(m for m in ('fsspec', 'dask', 'distributed', 's3fs') "
             "if m in sys.modules))")
    result = subprocess.run([str(Path(GSRWT).with_name("python")), "-c", probe], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120)
    assert result.stdout.strip() == "[]", result.stderr
    assert hashlib.sha256((tmp_path / "o" / "door_p8_t-2_f1500.jpg").read_bytes()).hexdigest()


def test_keys_that_name_no_path_are_errors_never_misread_or_written_outside(s3, tmp_path):
    """A key is any text: ``in//a.jpg``, ``in/./b.jpg`` and ``in/x/../../c.jpg`` name no
    relative path an output could keep (a path library reads the first as absolute, the
    second as ``in/b.jpg``, another object). Each is one error naming its URL; the good image
    beside them is rectified, locally and to the store, and nothing lands outside ``-o``."""
    fs, environment = s3
    fs.mkdir("oddkeys")
    door = (SAMPLES / "door_p8_t-2_f1500.jpg").read_bytes()
    for key in ("in/good.jpg", "in//double.jpg", "in/./dot.jpg", "in/x/../../up.jpg"):
        fs.pipe_file(f"oddkeys/{key}", door)
    for output in (str(tmp_path / "out"), "s3://oddkeys/out/"):
        result = run_gsrwt("rectify", "-r", "s3://oddkeys/in/", *POSE, "-o", output, cwd=tmp_path,
                           env=environment)
        assert result.returncode == 1, result.stderr
        errors = sorted(line for line in result.stderr.splitlines() if line.startswith("Error"))
        assert errors == [
            f"Error: s3://oddkeys/in/{key}: its key has an empty, '.' or '..' part, which names "
            "no output file; rename the object" for key in ("./dot.jpg", "/double.jpg",
                                                            "x/../../up.jpg")], result.stderr
        assert "1 ok, 0 skipped, 3 failed" in result.stderr
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == ["good.jpg",
                                                                         "gsrwt.csv"]
    assert sorted(name for name in fs.find("oddkeys/out")) == ["oddkeys/out/good.jpg",
                                                              "oddkeys/out/gsrwt.csv"]
