"""docs/medium/settle_table.py prints the per-width tables of docs/medium.md from a settle sweep and
its report: each cell must be the mean and standard error over the seeds of the runs' own values,
the moves column the settles' own displacements, and a width with a Bullet seed missing must say so.
Checked on a tiny settle sweep (two widths, two seeds, one Bullet run left out) against the runs as
confpack.study.load reads them, computed here without the report's tables."""
import contextlib
import importlib.util
import io
import json
import math
import os
import pathlib
import statistics
import subprocess
import sys

import pytest

import confpack
import confpack.study
from conftest import run_cli

SCRIPT = pathlib.Path(__file__).resolve().parents[2] / "docs" / "medium" / "settle_table.py"

SWEEP = {
    "format": "confpack-sweep", "version": 1, "name": "tiny-settle",
    "base": {"box": {"length_x": 3, "height": 7}, "compaction": {"time_limit": 2, "protocol": "quasi-static"}},
    "biperiodic_width": 3,
    "settle_with": "nscd",
    "vary": {"width": [3, 4], "backend": ["nscd", "bullet"], "replicas": 2},
}
# r0003 is Bullet's second seed at W = 3 (`confpack sweep --list`): left out, and so is its settle.
RUNS = "r0000,r0001,r0002,r0004,r0005,r0006,r0007"


@pytest.fixture(scope="module")
def settle_sweep(cli, tmp_path_factory):
    folder = tmp_path_factory.mktemp("settle")
    (folder / "tiny.json").write_text(json.dumps(SWEEP))
    run_cli(cli, "sweep", folder / "tiny.json", "--out", folder / "study", "--runs", RUNS, "-q")
    run_cli(cli, "report", folder / "study", "--out", folder / "report", "--no-figures")
    return folder / "study", folder / "report"


def load_script():
    spec = importlib.util.spec_from_file_location("settle_table", SCRIPT)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script


def printed_rows(sweep, report):
    script = load_script()
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        script.main(["settle_table.py", str(sweep), str(report), "MSP"])
    lines = out.getvalue().splitlines()
    assert lines[0] == script.HEADER
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in lines[2:]]


def values(runs, backend, key):
    """`key` of each of `runs` with this backend, in the order confpack.study.load gives them."""
    return [r[key] for r in runs if r["backend"] == backend]


def expected_cell(numbers, digits):
    if len(numbers) == 1:
        return f"{numbers[0]:.{digits}f} (1 seed)"
    error = statistics.stdev(numbers) / math.sqrt(len(numbers))
    return f"{statistics.mean(numbers):.{digits}f} ± {error:.{digits}f}"


def test_cells_are_the_seeds_mean_and_standard_error(settle_sweep):
    sweep, report = settle_sweep
    rows = printed_rows(sweep, report)
    runs = [r for r in confpack.study.load(sweep) if r["status"] == "done"]
    sides = ("nscd", "bullet", "bullet_settled")
    assert [row[0] for row in rows] == ["3 (Bullet: 1 seed)", "4"]
    for row, width in zip(rows, (3, 4)):
        mine = [r for r in runs if r["W"] == width]
        assert len(values(mine, "nscd", "solid_fraction")) == 2
        assert len(values(mine, "bullet_settled", "solid_fraction")) == (1 if width == 3 else 2)
        assert row[1:4] == [expected_cell(values(mine, s, "solid_fraction"), 4) for s in sides]
        assert row[4:7] == [expected_cell(values(mine, s, "coordination/Z"), 3) for s in sides]
        means = values(mine, "bullet_settled", "settle/mean_displacement")
        largest = values(mine, "bullet_settled", "settle/max_displacement")
        assert all(m > 0 for m in means)  # Bullet's piles, stopped at 2 t0, were not at rest
        assert row[7] == f"{statistics.mean(means):.3f} / {max(largest):.2f}"


def test_a_folder_without_a_report_is_one_message(tmp_path):
    # As docs/medium.md runs it: one line on stderr, a non-zero exit, nothing on stdout.
    env = dict(os.environ, PYTHONPATH=str(pathlib.Path(confpack.__file__).resolve().parents[1]))
    done = subprocess.run([sys.executable, str(SCRIPT), str(tmp_path), str(tmp_path / "report"), "MSP"],
                          capture_output=True, text=True, env=env)
    assert done.returncode != 0 and done.stdout == ""
    assert done.stderr.strip().count("\n") == 0
    assert done.stderr.startswith("settle_table.py: ") and "solid_fraction.csv" in done.stderr
