"""``gsrwt params`` through the real command: the thesis's tables, formats, sidecars, errors."""

from __future__ import annotations

import io

import pytest

from gsrwt_cli.tables.rows import PARAMS_COLUMNS
from tests.helpers.cli import run_gsrwt
from tests.helpers.printed import assert_table_prints_rows
from tests.helpers.tables import read_table
from tests.helpers.thesis import FIG_5_2, TABLE_5_1, TABLE_5_2


def test_issue_example_json():
    result = run_gsrwt("params", "--pan", "15", "--tilt", "30", "--focal", "280", "--format",
                       "json")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout, "json")
    assert list(row) == list(PARAMS_COLUMNS)
    assert row["delta_deg"] == pytest.approx(28.2, abs=0.05)
    assert row["a_px"] == pytest.approx(427.5, abs=0.05)
    assert row["gamma_deg"] == pytest.approx(-24.1, abs=0.05)
    assert row["vp_x"] == pytest.approx(376.8, abs=0.05)
    assert row["vp_y"] == pytest.approx(-201.9, abs=0.05)
    assert row["vp_col"] is None and row["horizon_in_image"] is None  # no size, no pixel frame


def write_thesis_sidecar(path):
    rows = [(pan, tilt) for pan, tilt, *_ in TABLE_5_1] + [FIG_5_2[:2]]
    rows += [(pan, tilt) for pan, tilt, *_ in TABLE_5_2]
    lines = ["image,pan,tilt,focal,width,height"]
    lines += [f"view_{pan}_{tilt}.png,{pan},{tilt},280,320,240" for pan, tilt in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_thesis_tables_through_the_cli(tmp_path):
    sidecar = write_thesis_sidecar(tmp_path / "thesis.csv")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "--format", "json")
    assert result.returncode == 0, result.stderr
    rows = {(r["pan_deg"], r["tilt_deg"]): r for r in read_table(result.stdout, "json")}
    for pan, tilt, delta, (vp_y, vp_x), a, gamma in TABLE_5_1:
        row = rows[(pan, tilt)]
        assert row["delta_deg"] == pytest.approx(delta, abs=1)
        assert row["a_px"] == pytest.approx(a, abs=1)
        assert row["gamma_deg"] == pytest.approx(gamma, abs=1)
        assert (row["vp_y"], row["vp_x"]) == pytest.approx((vp_y, vp_x), abs=2)
        # Pixel frame: principal point at (159.5, 119.5), x up = -row, y right = +col.
        assert (row["vp_col"], row["vp_row"]) == pytest.approx((159.5 + vp_y, 119.5 - vp_x), abs=2)
        assert row["vl_a"] ** 2 + row["vl_b"] ** 2 == pytest.approx(1, abs=1e-5)
        assert row["vl_a"] * row["vp_col"] + row["vl_b"] * row["vp_row"] + row["vl_c"] == (
            pytest.approx(0, abs=1e-3)
        )
        assert row["horizon_in_image"] is False
    pan, tilt, (vp_y, vp_x), a = FIG_5_2
    assert rows[(pan, tilt)]["a_px"] == pytest.approx(a, abs=1)
    row = rows[(pan, tilt)]
    assert (row["vp_y"], row["vp_x"]) == pytest.approx((vp_y, vp_x), abs=2)
    for pan, tilt, theta, foreshortening in TABLE_5_2:
        assert rows[(pan, tilt)]["theta_deg"] == pytest.approx(theta, abs=0.02)
        assert rows[(pan, tilt)]["foreshortening"] == pytest.approx(foreshortening, abs=0.01)


def test_yaml_mapping_and_list_with_defaults_agree_with_csv(tmp_path):
    csv_path = write_thesis_sidecar(tmp_path / "thesis.csv")
    expected = run_gsrwt("params", "--sidecar", str(csv_path), "-f", "csv")
    assert expected.returncode == 0, expected.stderr
    views = [(pan, tilt) for pan, tilt, *_ in TABLE_5_1] + [FIG_5_2[:2]]
    views += [(pan, tilt) for pan, tilt, *_ in TABLE_5_2]
    mapping = ["defaults: {focal: 280, width: 320, height: 240}"]
    mapping += [f"view_{p}_{t}.png: {{pan: {p}, tilt: {t}}}" for p, t in views]
    (tmp_path / "map.yaml").write_text("\n".join(mapping) + "\n")
    listing = ["- defaults: {focal: 280, width: 320, height: 240}"]
    listing += [f"- {{image: view_{p}_{t}.png, pan: {p}, tilt: {t}}}" for p, t in views]
    (tmp_path / "list.yml").write_text("\n".join(listing) + "\n")
    for name in ("map.yaml", "list.yml"):
        result = run_gsrwt("params", "--sidecar", str(tmp_path / name), "-f", "csv")
        assert result.returncode == 0, result.stderr
        assert result.stdout == expected.stdout


def test_options_fill_what_the_sidecar_leaves_out(tmp_path):
    (tmp_path / "v.csv").write_text("image,pan,tilt\na.jpg,15,30\n")
    result = run_gsrwt("params", "--sidecar", str(tmp_path / "v.csv"), "--focal", "280", "-f",
                       "jsonl")
    assert result.returncode == 0, result.stderr
    assert read_table(result.stdout, "jsonl")[0]["a_px"] == pytest.approx(427.46, abs=0.01)


def test_gsrwt_parameters_as_input_give_back_the_pose(tmp_path):
    (tmp_path / "v.csv").write_text(
        "image,delta,a,gamma,focal\nb.jpg,28.186785,427.462305,-24.1,280\n"
    )
    result = run_gsrwt("params", "--sidecar", str(tmp_path / "v.csv"), "-f", "jsonl")
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout, "jsonl")
    assert (row["pan_deg"], row["tilt_deg"]) == pytest.approx((15, 30), abs=1e-5)


@pytest.mark.parametrize("fmt", ["csv", "tsv", "json", "jsonl", "markdown", "table"])
def test_every_format_carries_the_same_values(fmt):
    result = run_gsrwt("params", "--pan", "30", "--tilt", "15", "--focal", "280", "--width", "320",
                       "--height", "240", "-f", fmt)
    assert result.returncode == 0, result.stderr
    (row,) = read_table(result.stdout, fmt)
    delta, horizon = float(row["delta_deg"]), row["horizon_in_image"]
    assert row["image"] in ("", None)  # no image: an empty cell, or null in JSON
    assert delta == pytest.approx(65.85, abs=0.01)
    assert horizon in (False, "false")


def test_pipe_defaults_to_csv():
    result = run_gsrwt("params", "--pan", "15", "--tilt", "30", "--focal", "280")
    assert result.returncode == 0
    assert result.stdout.splitlines()[0] == ",".join(PARAMS_COLUMNS)


def test_frontal_view_has_no_vanishing_point():
    result = run_gsrwt("params", "--pan", "0", "--tilt", "0", "--focal", "280", "--width", "320",
                       "--height", "240", "-f", "json")
    (row,) = read_table(result.stdout, "json")
    assert row["a_px"] is None and row["vp_x"] is None and row["vl_a"] is None
    assert row["theta_deg"] == 0 and row["foreshortening"] == 1
    assert row["horizon_in_image"] is False


def test_horizon_in_image_when_the_vanishing_line_crosses_it():
    result = run_gsrwt("params", "--pan", "80", "--tilt", "0", "--focal", "280", "--width", "320",
                       "--height", "240", "-f", "json")
    assert read_table(result.stdout, "json")[0]["horizon_in_image"] is True


BAD_ROWS = [
    ("a.jpg,15,95,280", "line 2, field 'tilt'", "strictly between -90 and 90"),
    ("a.jpg,-90,10,280", "line 2, field 'pan'", "strictly between -90 and 90"),
    ("a.jpg,15,30,-3", "line 2, field 'focal'", "must be positive"),
    ("a.jpg,15,30,0", "line 2, field 'focal'", "must be positive"),
    ("a.jpg,abc,30,280", "line 2, field 'pan'", "not a number"),
    ("a.jpg,nan,30,280", "line 2, field 'pan'", "must be finite"),
    ("a.jpg,15,inf,280", "line 2, field 'tilt'", "must be finite"),
    ("a.jpg,15,30,", "line 2: missing field 'focal'", ""),
]


@pytest.mark.parametrize(("row", "where", "what"), BAD_ROWS)
def test_bad_rows_name_file_row_and_field(tmp_path, row, where, what):
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\n" + row + "\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar))
    assert result.returncode == 2
    assert result.stdout == ",".join(PARAMS_COLUMNS) + "\n"  # the header, no row
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith(f"Error: {sidecar} {where}")
    assert what in lines[0]
    assert "Traceback" not in result.stderr


def test_every_bad_row_is_reported(tmp_path):
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\na,15,95,280\nb,15,30,280\nc,15,30,-3\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 2
    assert [row["image"] for row in read_table(result.stdout)] == ["b"]
    lines = result.stderr.splitlines()
    assert lines == [
        f"Error: {sidecar} line 2, field 'tilt': tilt must be strictly between -90 and 90 "
        "degrees (the camera cannot see the wall otherwise), got 95",
        f"Error: {sidecar} line 4, field 'focal': focal must be positive, got -3",
    ]


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("missing.csv", None, "missing.csv: no such file"),
        ("views.csv", "pan,tilt,focal\n15,30,280\n", "views.csv line 1: missing column 'image'"),
        ("views.csv", "", "views.csv: empty file"),
        ("views.yaml", "a.jpg: [1, 2\n", "views.yaml line 2"),
        ("views.yaml", "- {image: a.jpg, pan: 1, tilt: 2, focal: x}\n",
         "views.yaml record 1, field 'focal': not a number"),
        ("views.txt.gz", "x", "unknown sidecar type"),
    ],
)
def test_bad_sidecar_files(tmp_path, name, content, message):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    result = run_gsrwt("params", "--sidecar", str(path))
    assert result.returncode == 2
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert message in result.stderr
    assert "Traceback" not in result.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--pan", "15", "--tilt", "30"], "Error: missing option --focal"),
        (["--pan", "15", "--tilt", "95", "--focal", "280"], "Error: option --tilt: tilt must"),
        (["--pan", "15", "--tilt", "30", "--focal", "-3"], "Error: option --focal: focal must"),
        (["--pan", "nan", "--tilt", "30", "--focal", "280"],
         "Error: Invalid value for '--pan': must be finite, got 'nan'"),
        (["--pan", "x", "--tilt", "30", "--focal", "280"],
         "Error: Invalid value for '--pan': expected a finite decimal number in ASCII digits, "
         "such as -2.5 or 1e3, got 'x'"),
        (["--pan", "1", "--tilt", "30", "--focal", "280", "--cx", "3"], "cx and cy"),
    ],
)
def test_bad_options(args, message):
    result = run_gsrwt("params", *args)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_rows_stream_out_around_a_bad_row(tmp_path):
    """Rows are printed as they are computed: the good rows before and after a bad one are
    out, the bad one is reported naming its line, and the exit status says the input was bad."""
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\na,15,30,280\nb,15,95,280\nc,-20,10,400\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 2
    rows = read_table(result.stdout)
    assert [row["image"] for row in rows] == ["a", "c"]
    expected = run_gsrwt("params", "--pan", "-20", "--tilt", "10", "--focal", "400", "-f", "csv")
    assert rows[1] == {**read_table(expected.stdout)[0], "image": "c"}
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: {sidecar} line 3, field 'tilt'")


def test_an_image_twice_is_two_rows_for_params_but_refused_by_rectify(tmp_path):
    """params looks nothing up by image, so it streams a sidecar without remembering names
    (memory flat in the rows); rectify, which looks images up, refuses the ambiguity."""
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\na.png,1,2,280\na.png,3,4,280\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 0
    assert [row["pan_deg"] for row in read_table(result.stdout)] == ["1", "3"]
    refused = run_gsrwt("rectify", str(tmp_path), "--sidecar", str(sidecar), "-o",
                        str(tmp_path / "out"))
    assert refused.returncode == 2
    assert "line 3: image 'a.png' is already in" in refused.stderr


@pytest.mark.parametrize("fmt", ["csv", "tsv", "json"])
def test_a_big_plain_sidecar_through_the_command_is_its_views_row_by_row(tmp_path, fmt):
    """``params --sidecar`` takes a CSV's plain chunks as columns (cells straight from the
    csv module, option defaults as constant columns): through the real command, the output
    is what each row's own view writes (cell for cell, :mod:`printed`), for a file of several
    chunks with an ignored column, an empty known column, names that need quoting, and a
    malformed row in the third chunk (the rows before it are out; exit 2 naming its line)."""
    import random

    from gsrwt_cli.inputs.records import view_from_values
    from gsrwt_cli.inputs.sidecar import CHUNK_ROWS
    from gsrwt_cli.tables.rows import params_row

    rng = random.Random(fmt)
    lines, views = ["image,pan,tilt,focal,height,notes,roll"], []
    for index in range(2 * CHUNK_ROWS + 300):
        pan, tilt = f"{rng.uniform(-80, 80):.3f}", f"{rng.uniform(-80, 80):.3f}"
        focal, height = f"{rng.uniform(100, 3000):.1f}", str(rng.randint(100, 4000))
        name = f'"shot, {index}.jpg"' if index % 500 == 7 else f"img{index}.jpg"
        lines.append(f"{name},{pan},{tilt},{focal},{height},whatever,")
        views.append((name.strip('"'), {"pan": pan, "tilt": tilt, "focal": focal,
                                        "height": height, "width": "640"}))
    bad = 2 * CHUNK_ROWS + 100
    lines[bad + 1] = 'broken,"10,5,300'  # an unclosed quote: the csv module refuses the rest
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("\n".join(lines) + "\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "--width", "640", "-f", fmt)
    assert result.returncode == 2
    assert result.stderr.startswith(f"Error: {sidecar} line {bad + 2}")
    rows = [params_row(view_from_values(values, "x"), image) for image, values in views[:bad]]
    assert_table_prints_rows(result.stdout, fmt, rows, PARAMS_COLUMNS)


def test_a_bad_value_after_plain_chunks_is_its_own_error_and_the_rest_are_printed(tmp_path):
    """A row that is no valid view, deep in a big file after chunks computed as columns: its
    chunk goes row by row, the error names its line, every other row (before and after it,
    in that chunk and the next) is printed as its view gives it, and the exit status is 2."""
    from gsrwt_cli.inputs.records import view_from_values
    from gsrwt_cli.inputs.sidecar import CHUNK_ROWS
    from gsrwt_cli.tables.rows import params_row
    from gsrwt_cli.tables.writer import TableWriter

    lines, views = ["image,pan,tilt,focal"], []
    for index in range(2 * CHUNK_ROWS):
        pan, tilt = f"{(index % 170) - 85}.5", f"{(index * 7) % 170 - 85}.25"
        lines.append(f"i{index}.jpg,{pan},{tilt},300")
        views.append((f"i{index}.jpg", {"pan": pan, "tilt": tilt, "focal": "300"}))
    bad = CHUNK_ROWS + 77
    lines[bad + 1] = f"i{bad}.jpg,10,95,300"
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("\n".join(lines) + "\n")
    result = run_gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 2
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: {sidecar} line {bad + 2}, field 'tilt'")
    expected = io.StringIO()
    writer = TableWriter(expected, PARAMS_COLUMNS, "csv")
    for index, (image, values) in enumerate(views):
        if index != bad:
            writer.write_row(params_row(view_from_values(values, "x"), image))
    writer.close()
    assert result.stdout == expected.getvalue()
