"""``gsrwt params`` through the real command: the thesis's tables, formats, sidecars, errors."""

from __future__ import annotations

import csv
import io
import json

import pytest
from click.testing import CliRunner
from printed import PrintedComparison, allowed, assert_table_prints_rows
from test_geometry import FIG_5_2, TABLE_5_1, TABLE_5_2

from gsrwt_cli.cli import main
from gsrwt_cli.tables.rows import PARAMS_COLUMNS


def invoke(*args: str):
    return CliRunner().invoke(main, list(args))


def test_issue_example_json(gsrwt):
    result = gsrwt("params", "--pan", "15", "--tilt", "30", "--focal", "280", "--format", "json")
    assert result.returncode == 0, result.stderr
    (row,) = json.loads(result.stdout)
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


def test_thesis_tables_through_the_cli(tmp_path, gsrwt):
    sidecar = write_thesis_sidecar(tmp_path / "thesis.csv")
    result = gsrwt("params", "--sidecar", str(sidecar), "--format", "json")
    assert result.returncode == 0, result.stderr
    rows = {(r["pan_deg"], r["tilt_deg"]): r for r in json.loads(result.stdout)}
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
    expected = invoke("params", "--sidecar", str(csv_path), "-f", "csv")
    assert expected.exit_code == 0, expected.output
    views = [(pan, tilt) for pan, tilt, *_ in TABLE_5_1] + [FIG_5_2[:2]]
    views += [(pan, tilt) for pan, tilt, *_ in TABLE_5_2]
    mapping = ["defaults: {focal: 280, width: 320, height: 240}"]
    mapping += [f"view_{p}_{t}.png: {{pan: {p}, tilt: {t}}}" for p, t in views]
    (tmp_path / "map.yaml").write_text("\n".join(mapping) + "\n")
    listing = ["- defaults: {focal: 280, width: 320, height: 240}"]
    listing += [f"- {{image: view_{p}_{t}.png, pan: {p}, tilt: {t}}}" for p, t in views]
    (tmp_path / "list.yml").write_text("\n".join(listing) + "\n")
    for name in ("map.yaml", "list.yml"):
        result = invoke("params", "--sidecar", str(tmp_path / name), "-f", "csv")
        assert result.exit_code == 0, result.output
        assert result.output == expected.output


def test_options_fill_what_the_sidecar_leaves_out(tmp_path):
    (tmp_path / "v.csv").write_text("image,pan,tilt\na.jpg,15,30\n")
    result = invoke("params", "--sidecar", str(tmp_path / "v.csv"), "--focal", "280", "-f", "jsonl")
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["a_px"] == pytest.approx(427.46, abs=0.01)


def test_gsrwt_parameters_as_input_give_back_the_pose(tmp_path):
    (tmp_path / "v.csv").write_text(
        "image,delta,a,gamma,focal\nb.jpg,28.186785,427.462305,-24.1,280\n"
    )
    result = invoke("params", "--sidecar", str(tmp_path / "v.csv"), "-f", "jsonl")
    assert result.exit_code == 0, result.output
    row = json.loads(result.output)
    assert (row["pan_deg"], row["tilt_deg"]) == pytest.approx((15, 30), abs=1e-5)


@pytest.mark.parametrize("fmt", ["csv", "tsv", "json", "jsonl", "markdown", "table"])
def test_every_format_carries_the_same_values(fmt):
    result = invoke("params", "--pan", "30", "--tilt", "15", "--focal", "280",
                    "--width", "320", "--height", "240", "-f", fmt)
    assert result.exit_code == 0, result.output
    text = result.output
    if fmt in ("csv", "tsv"):
        rows = list(csv.DictReader(io.StringIO(text), delimiter="\t" if fmt == "tsv" else ","))
        delta, horizon = float(rows[0]["delta_deg"]), rows[0]["horizon_in_image"]
    elif fmt == "json":
        rows = json.loads(text)
        delta, horizon = rows[0]["delta_deg"], rows[0]["horizon_in_image"]
    elif fmt == "jsonl":
        rows = [json.loads(line) for line in text.splitlines()]
        delta, horizon = rows[0]["delta_deg"], rows[0]["horizon_in_image"]
    else:
        lines = [line for line in text.splitlines() if not line.startswith("|--")]
        split = (lambda s: [c.strip() for c in s.strip("|").split("|")]) if fmt == "markdown" \
            else str.split
        header, values = split(lines[0]), split(lines[1])
        # In the aligned table the empty image cell is blank space.
        cells = dict(zip(header[1:], values)) if fmt == "table" else dict(zip(header, values))
        delta, horizon = float(cells["delta_deg"]), cells["horizon_in_image"]
        assert len(lines) == 2
    assert delta == pytest.approx(65.85, abs=0.01)
    assert horizon in (False, "false")


def test_pipe_defaults_to_csv(gsrwt):
    result = gsrwt("params", "--pan", "15", "--tilt", "30", "--focal", "280")
    assert result.returncode == 0
    assert result.stdout.splitlines()[0] == ",".join(PARAMS_COLUMNS)


def test_frontal_view_has_no_vanishing_point():
    result = invoke("params", "--pan", "0", "--tilt", "0", "--focal", "280",
                    "--width", "320", "--height", "240", "-f", "json")
    (row,) = json.loads(result.output)
    assert row["a_px"] is None and row["vp_x"] is None and row["vl_a"] is None
    assert row["theta_deg"] == 0 and row["foreshortening"] == 1
    assert row["horizon_in_image"] is False


def test_horizon_in_image_when_the_vanishing_line_crosses_it():
    result = invoke("params", "--pan", "80", "--tilt", "0", "--focal", "280",
                    "--width", "320", "--height", "240", "-f", "json")
    assert json.loads(result.output)[0]["horizon_in_image"] is True


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
def test_bad_rows_name_file_row_and_field(tmp_path, gsrwt, row, where, what):
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\n" + row + "\n")
    result = gsrwt("params", "--sidecar", str(sidecar))
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
    result = CliRunner().invoke(main, ["params", "--sidecar", str(sidecar), "-f", "csv"])
    assert result.exit_code == 2
    assert [row["image"] for row in csv.DictReader(io.StringIO(result.stdout))] == ["b"]
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
def test_bad_sidecar_files(tmp_path, gsrwt, name, content, message):
    path = tmp_path / name
    if content is not None:
        path.write_text(content)
    result = gsrwt("params", "--sidecar", str(path))
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
def test_bad_options(gsrwt, args, message):
    result = gsrwt("params", *args)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr


def test_rows_stream_out_around_a_bad_row(tmp_path, gsrwt):
    """Rows are printed as they are computed: the good rows before and after a bad one are
    out, the bad one is reported naming its line, and the exit status says the input was bad."""
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\na,15,30,280\nb,15,95,280\nc,-20,10,400\n")
    result = gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 2
    rows = list(csv.DictReader(io.StringIO(result.stdout)))
    assert [row["image"] for row in rows] == ["a", "c"]
    expected = gsrwt("params", "--pan", "-20", "--tilt", "10", "--focal", "400", "-f", "csv")
    assert rows[1] == {**list(csv.DictReader(io.StringIO(expected.stdout)))[0], "image": "c"}
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"Error: {sidecar} line 3, field 'tilt'")


def test_an_image_twice_is_two_rows_for_params_but_refused_by_rectify(tmp_path, gsrwt):
    """params looks nothing up by image, so it streams a sidecar without remembering names
    (memory flat in the rows); rectify, which looks images up, refuses the ambiguity."""
    sidecar = tmp_path / "views.csv"
    sidecar.write_text("image,pan,tilt,focal\na.png,1,2,280\na.png,3,4,280\n")
    result = gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
    assert result.returncode == 0
    assert [row["pan_deg"] for row in csv.DictReader(io.StringIO(result.stdout))] == ["1", "3"]
    refused = gsrwt("rectify", str(tmp_path), "--sidecar", str(sidecar), "-o",
                    str(tmp_path / "out"))
    assert refused.returncode == 2
    assert "line 3: image 'a.png' is already in" in refused.stderr


def _random_record(rng, index: int) -> tuple[str, dict[str, str], str]:
    """A sidecar record of a random kind: plain, with size or principal point, frontal,
    invalid, near the horizon limit, rolled (the long way)."""
    values = {"pan": f"{rng.uniform(-89.99, 89.99):.3f}",
              "tilt": f"{rng.uniform(-89.99, 89.99):.3f}", "focal": f"{rng.uniform(1, 3000):.2f}"}
    kind = rng.randrange(10)
    extra = [
        {"width": str(rng.randint(1, 5000)), "height": str(rng.randint(1, 5000))},
        {"cx": f"{rng.uniform(-100, 1000):.1f}", "cy": f"{rng.uniform(-100, 1000):.1f}"},
        {"cx": "10", "cy": "20", "width": "30", "height": "40"},
        {"pan": "0", "tilt": "0", "width": "640", "height": "480"},
        {"pan": "0", "tilt": "-0"},
        {"tilt": "95"},
        {"width": "64.5", "height": "3"},
        {"pan": "89.99999999", "tilt": "89.9999999", "focal": "1"},
        {"width": "640", "cx": "nan", "cy": "1"},
        {"roll": "5", "width": "640", "height": "480"},
    ][kind]
    return f"i{index}.png", {**values, **extra}, f"views.csv line {index + 2}"


def test_views_computed_together_print_what_their_views_print():
    """``params --sidecar`` computes square-pixel pinholes many at once: every row prints
    what the record's own view prints (a second implementation: values within
    :data:`printed.TOLERANCE`, cells identical but where a value lies that close to a
    rounding boundary), and every error is the view's own."""
    import random

    from gsrwt_cli.inputs.records import RecordError, view_from_values
    from gsrwt_cli.tables.rows import params_row, params_rows

    rng = random.Random(7)
    records = [_random_record(rng, index) for index in range(20_000)]
    fast = 0
    compare = PrintedComparison()
    for (image, values, where), row in zip(records, params_rows(records)):
        try:
            expected = params_row(view_from_values(values, where), image)
        except RecordError as error:
            assert isinstance(row, RecordError) and str(row) == str(error)
            continue
        assert isinstance(row, dict) and row.keys() == expected.keys(), (values, row)
        for name, value in expected.items():
            compare.values(row[name], value, (name, values))
        fast += "roll" not in values
    assert fast > 8_000  # valid rows without roll: computed together
    compare.assert_few_flips()


@pytest.mark.parametrize("kind", ["size", "principal point", "neither", "frontal rows"])
def test_a_plain_csv_chunk_computed_as_columns_writes_what_its_views_would(kind):
    """A chunk of plain CSV rows (decimal text, valid square-pixel pinholes) is computed and
    written as columns: the same csv and json, byte for byte, as each row's own view gives."""
    import random

    from gsrwt_cli.inputs.records import view_from_values
    from gsrwt_cli.tables.rows import PARAMS_CHUNK, ParamsBlock, params_row, params_rows
    from gsrwt_cli.tables.writer import TableWriter

    rng = random.Random(kind)
    records = []
    for index in range(PARAMS_CHUNK + 100):  # a whole chunk, then part of one
        values = {"pan": f"{rng.uniform(-85, 85):.4f}", "tilt": f"{rng.uniform(-85, 85):.4f}",
                  "focal": f"{rng.uniform(50, 4000):.3f}"}
        if kind == "frontal rows" and index % 3 == 0:
            values.update(pan="0", tilt="-0.0")
        if kind in ("size", "frontal rows"):
            values.update(width=str(rng.randint(1, 6000)), height=str(rng.randint(1, 6000)))
        elif kind == "principal point":
            values.update(cx=f"{rng.uniform(-50, 900):.2f}", cy=f"{rng.uniform(-50, 900):.2f}")
        records.append((f"img{index}.jpg", values, f"views.csv line {index + 2}"))
    produced = list(params_rows(records))
    assert all(isinstance(item, ParamsBlock) for item in produced) and len(produced) == 2
    rows = [params_row(view_from_values(values, where), image)
            for image, values, where in records]
    for fmt in ("csv", "json"):
        fast = io.StringIO()
        writer = TableWriter(fast, PARAMS_COLUMNS, fmt)
        for block in produced:
            writer.write_columns(block.columns, block.count)
        writer.close()
        assert_table_prints_rows(fast.getvalue(), fmt, rows, PARAMS_COLUMNS)


def test_a_chunk_with_one_odd_cell_is_computed_row_by_row():
    """One cell that is not plain decimal text (here ``1_000``, which Python's float reads)
    sends its chunk the long way: that row is the error its view gives."""
    from gsrwt_cli.inputs.records import RecordError
    from gsrwt_cli.tables.rows import ParamsBlock, params_rows

    records = [(f"i{index}", {"pan": "10", "tilt": "5", "focal": "300"}, f"v line {index}")
               for index in range(50)]
    records[7] = ("i7", {"pan": "10", "tilt": "5", "focal": "1_000"}, "v line 7")
    produced = list(params_rows(records))
    assert not any(isinstance(item, ParamsBlock) for item in produced)
    assert isinstance(produced[7], RecordError) and "not a number" in str(produced[7])
    assert sum(isinstance(item, dict) for item in produced) == 49


@pytest.mark.parametrize("fmt", ["csv", "tsv", "json"])
def test_a_big_plain_sidecar_through_the_command_is_its_views_row_by_row(tmp_path, gsrwt, fmt):
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
    result = gsrwt("params", "--sidecar", str(sidecar), "--width", "640", "-f", fmt)
    assert result.returncode == 2
    assert result.stderr.startswith(f"Error: {sidecar} line {bad + 2}")
    rows = [params_row(view_from_values(values, "x"), image) for image, values in views[:bad]]
    assert_table_prints_rows(result.stdout, fmt, rows, PARAMS_COLUMNS)


def test_one_plain_view_computed_without_numpy_prints_its_views_row():
    """``gsrwt params`` with options computes a plain square-pixel pinhole by the math
    module alone (:mod:`gsrwt_cli.geometry.pinhole`): for random options, frontal views, horizons
    near
    the principal point and every combination of size and principal point, the row prints
    what the view's row prints (:mod:`printed`: a second implementation, compared as the
    table shows it) type for type, and None where the view refuses (its error is then the
    view's). The two may disagree on refusing only where the horizon's offset from the
    principal point lies within rounding of the bound."""
    import math
    import random

    from gsrwt_cli.geometry.bounds import MIN_HORIZON_OFFSET_PX

    def near_the_horizon_bound(numbers: tuple[float, ...]) -> bool:
        pan, tilt, focal = math.radians(numbers[0]), math.radians(numbers[1]), numbers[2]
        sin_theta = math.hypot(math.sin(pan), math.cos(pan) * math.sin(tilt))
        offset = focal * math.cos(pan) * math.cos(tilt) / sin_theta
        return abs(offset - MIN_HORIZON_OFFSET_PX) <= allowed(MIN_HORIZON_OFFSET_PX)

    from gsrwt_cli.geometry.pinhole import pinhole_numbers, pinhole_params_row
    from gsrwt_cli.inputs.records import RecordError, view_from_values
    from gsrwt_cli.tables.rows import params_row

    rng = random.Random(11)
    checked = refused = 0
    compare = PrintedComparison()
    for index in range(20_000):
        values = {"pan": rng.choice([rng.uniform(-89.99, 89.99), 0.0, -0.0, 1e-10, 89.9999]),
                  "tilt": rng.choice([rng.uniform(-89.99, 89.99), 0.0, 2e-9, -89.99999]),
                  "focal": rng.choice([rng.uniform(0.1, 5000), 280.0, 1e-3])}
        kind = index % 4
        if kind in (1, 3):
            values.update(width=rng.randint(1, 8000), height=rng.randint(1, 8000))
        if kind in (2, 3):
            values.update(cx=rng.uniform(-100, 9000), cy=rng.uniform(-100, 9000))
        if index % 7 == 0:
            values["distance"] = rng.uniform(0.01, 100)
        numbers = pinhole_numbers(values, "options")
        assert numbers is not None
        row = pinhole_params_row(numbers)
        try:
            expected = params_row(view_from_values(values, "options"))
        except RecordError:
            assert row is None or near_the_horizon_bound(numbers), values
            refused += 1
            continue
        if row is None:
            assert near_the_horizon_bound(numbers), values
            continue
        assert list(row) == list(expected), values
        for name, value in expected.items():
            compare.values(row[name], value, (name, values))
        checked += 1
    assert checked > 8_000 and refused > 1_000
    compare.assert_few_flips()
    assert pinhole_numbers({"pan": 10, "tilt": 5, "focal": 300, "roll": 2}, "x") is None
    assert pinhole_numbers({"pan": 10, "tilt": 95, "focal": 300}, "x") is None


def test_a_bad_value_after_plain_chunks_is_its_own_error_and_the_rest_are_printed(tmp_path, gsrwt):
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
    result = gsrwt("params", "--sidecar", str(sidecar), "-f", "csv")
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
