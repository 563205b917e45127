"""Timestamped pose files (``inputs/pose_log.py``): CSV and YAML, pan/tilt/roll or a
quaternion, and every fault named by its line."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from gsrwt_cli.geometry.rotations import (
    pose_from_rotation,
    quaternion_from_pose,
    rotation_from_pose,
)
from gsrwt_cli.inputs.pose_log import PoseLogError, load_pose_log


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_csv_rows_in_any_order_with_quaternions_and_focal(tmp_path: Path) -> None:
    qw, qx, qy, qz = quaternion_from_pose(20, 10, 3)
    path = write(tmp_path, "p.csv", "time,qw,qx,qy,qz,focal,extra\n"
                 f"1.0,{qw},{qx},{qy},{qz},700,x\n0.0,1,0,0,0,600,y\n")
    log = load_pose_log(path)
    timeline = log.timeline(max_gap=0.5)
    assert [sample.time for sample in timeline.samples] == [0.0, 1.0]
    np.testing.assert_allclose(timeline.samples[1].rotation, rotation_from_pose(20, 10, 3),
                               atol=1e-12)
    assert timeline.at(0.5).numbers == {"focal": pytest.approx(650)}
    assert pose_from_rotation(timeline.samples[0].rotation).pan == pytest.approx(0)


def test_yaml_with_defaults(tmp_path: Path) -> None:
    path = write(tmp_path, "p.yaml", "- defaults: {focal: 500, cx: 160}\n"
                 "- {time: 0, pan: 5, tilt: 10}\n- {time: 0.5, pan: 15, tilt: 10, roll: 2}\n")
    log = load_pose_log(path)
    assert log.defaults == {"focal": 500.0, "cx": 160.0}
    assert pose_from_rotation(log.samples[1].rotation).roll == pytest.approx(2)


@pytest.mark.parametrize(("text", "message"), [
    ("time,pan,tilt\n0,1,2\n0.5,1,2\n0,3,4\n",
     "p.csv line 4: time 0 is already given in line 2"),
    ("pan,tilt\n0,1\n", "p.csv line 1: missing column 'time'"),
    ("time,pan,tilt\n0,1\n", "p.csv line 2: missing field 'tilt'"),
    ("time,pan,tilt\nnan,1,2\n", "p.csv line 2, field 'time': must be finite"),
    ("time,pan,tilt\n0,95,2\n", "p.csv line 2, field 'pan': pan must be strictly between"),
    ("time,pan,tilt,qw,qx,qy,qz\n0,1,2,1,0,0,0\n", "give one pose, not pan/tilt and a quat"),
    ("time,qw,qx,qy\n0,1,0,0\n", "missing field 'qz'"),
    ("time,qw,qx,qy,qz\n0,2,0,0,0\n", "p.csv line 2, field 'qw': the quaternion"),
    ("time,pan,tilt\n", "p.csv: no poses"),
    ("time,pan,tilt\n0,1,2,3\n", "p.csv line 2: 4 cells but the header has 3"),
])
def test_faults_name_the_line(tmp_path: Path, text: str, message: str) -> None:
    path = write(tmp_path, "p.csv", text)
    with pytest.raises(PoseLogError, match=re.escape(message)):
        load_pose_log(path).timeline(0.5)


def test_yaml_faults(tmp_path: Path) -> None:
    with pytest.raises(PoseLogError, match="p.yaml record 2: missing field 'time'"):
        load_pose_log(write(tmp_path, "p.yaml", "- {time: 0, pan: 1, tilt: 2}\n"
                            "- {pan: 1, tilt: 2}\n"))
    with pytest.raises(PoseLogError, match="unknown field 'pan'"):
        load_pose_log(write(tmp_path, "p.yaml", "- defaults: {pan: 3}\n"))
    with pytest.raises(PoseLogError, match="expected a list"):
        load_pose_log(write(tmp_path, "p.yaml", "time: 3\n"))
    with pytest.raises(PoseLogError, match="unknown pose file type"):
        load_pose_log(write(tmp_path, "p.json", "[]"))
    # what is wrong with a path that is no pose file: missing, a folder, a device
    with pytest.raises(PoseLogError, match="none: no such file$"):
        load_pose_log(tmp_path / "none")
    with pytest.raises(PoseLogError, match=": is a directory, not a pose file$"):
        load_pose_log(tmp_path)
    with pytest.raises(PoseLogError, match="unknown pose file type ''"):
        load_pose_log("/dev/null")  # it exists: it was called "no such file"
