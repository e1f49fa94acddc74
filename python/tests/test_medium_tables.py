"""docs/medium/settle_table.py and equal_time_table.py print the per-width tables of docs/medium.md
from a settle sweep, an equal-time sweep and their reports: each cell must be the mean and standard
error over the seeds of the runs' own values, the moves column the settles' own displacements, the
force ratios and times Bullet's own runs', and a width with a Bullet seed missing must say so.
Checked on tiny sweeps (two widths, two seeds; one Bullet run left out of the settle sweep) against
the runs as confpack.study.load reads them, computed here without the report's tables."""
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

SCRIPTS = pathlib.Path(__file__).resolve().parents[2] / "docs" / "medium"

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


def load_script(name):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    return script


def printed_lines(name, *args):
    """What the script `name` prints for `args`, its header checked and its rule dropped."""
    script = load_script(name)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        script.main([f"{name}.py", *map(str, args)])
    lines = out.getvalue().splitlines()
    assert lines[0] == script.HEADER
    return lines[2:]


def cells(line):
    return [cell.strip() for cell in line.strip("|").split("|")]


def printed_rows(sweep, report):
    return [cells(line) for line in printed_lines("settle_table", sweep, report, "MSP")]


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


def test_runs_are_picked_by_their_percentage_of_small_grains(cli, tmp_path):
    # x_S is a percentage in the sweep file, in confpack.study.load and on the scripts' command
    # line (BSP 25): a bidisperse Bullet pile, stopped at 0.5 t0, is found by 25 and not by 0.25.
    sweep = {"format": "confpack-sweep", "version": 1, "name": "tiny-bsp",
             "base": {"box": {"length_x": 3, "height": 7}, "compaction": {"time_limit": 0.5}},
             "vary": {"width": [3], "backend": ["bullet"], "small_fraction": [25]}}
    (tmp_path / "bsp.json").write_text(json.dumps(sweep))
    run_cli(cli, "sweep", tmp_path / "bsp.json", "--out", tmp_path / "study", "-q")
    script = load_script("settle_table")
    runs = script.family_runs(tmp_path / "study", "bullet", "BSP", 25.0)
    assert list(runs) == [(3.0, False)] and [r["x_S"] for r in runs[(3.0, False)]] == [25.0]
    assert script.family_runs(tmp_path / "study", "bullet", "BSP", 0.25) == {}


@pytest.mark.parametrize("name, reports", [("settle_table", 1), ("equal_time_table", 2)])
def test_a_folder_without_a_report_is_one_message(tmp_path, name, reports):
    # As docs/medium.md runs them: one line on stderr, a non-zero exit, nothing on stdout.
    env = dict(os.environ, PYTHONPATH=str(pathlib.Path(confpack.__file__).resolve().parents[1]))
    args = [str(tmp_path)] + [str(tmp_path / "report")] * reports + ["MSP"]
    done = subprocess.run([sys.executable, str(SCRIPTS / f"{name}.py"), *args],
                          capture_output=True, text=True, env=env)
    assert done.returncode != 0 and done.stdout == ""
    assert done.stderr.strip().count("\n") == 0
    assert done.stderr.startswith(f"{name}.py: ") and "solid_fraction.csv" in done.stderr


# nscd's fall ends at 3 t0 (then its finisher), so Bullet's runs here have 3 t0 where the settle
# sweep's had their own limit of 2.
EQUAL_TIME = dict(SWEEP, name="tiny-equal-time", equal_time="nscd",
                  base={"box": SWEEP["base"]["box"],
                        "compaction": dict(SWEEP["base"]["compaction"], time_limit=4, fall_time_limit=3)})
del EQUAL_TIME["settle_with"]


@pytest.fixture(scope="module")
def equal_time_sweep(cli, tmp_path_factory):
    folder = tmp_path_factory.mktemp("equal")
    (folder / "tiny.json").write_text(json.dumps(EQUAL_TIME))
    run_cli(cli, "sweep", folder / "tiny.json", "--out", folder / "study", "-q")
    run_cli(cli, "report", folder / "study", "--out", folder / "report", "--no-figures")
    return folder / "study", folder / "report"


def test_equal_time_cells_are_each_sweeps_own_runs(equal_time_sweep, settle_sweep):
    sweep, report = equal_time_sweep
    settled_sweep, settled_report = settle_sweep
    lines = printed_lines("equal_time_table", sweep, report, settled_report, "MSP")
    rows, times = [cells(line) for line in lines[:-1]], lines[-1]
    equal = [r for r in confpack.study.load(sweep) if r["status"] == "done"]
    settled = [r for r in confpack.study.load(settled_sweep) if r["status"] == "done"]
    assert [row[0] for row in rows] == ["3", "4"]
    spans = []
    for row, width in zip(rows, (3, 4)):
        mine = [r for r in equal if r["W"] == width]
        stopped = [r for r in settled if r["W"] == width]
        assert row[1:4] == [expected_cell(values(mine, "nscd", "solid_fraction"), 4),
                            expected_cell(values(stopped, "bullet", "solid_fraction"), 4),
                            expected_cell(values(mine, "bullet", "solid_fraction"), 4)]
        assert row[4:8] == [expected_cell(values(mine, "nscd", "coordination/Z"), 3),
                            expected_cell(values(stopped, "bullet", "coordination/Z"), 3),
                            expected_cell(values(mine, "bullet", "coordination/Z"), 3),
                            expected_cell(values(stopped, "bullet_settled", "coordination/Z"), 3)]
        ratios = values(mine, "bullet", "equilibrium/max_force_ratio")
        assert min(ratios) >= 0.01  # these piles are far from rest: two decimals each
        low, high = f"{min(ratios):.2f}", f"{max(ratios):.2f}"
        assert row[8] == (low if low == high else f"{low} to {high}")
        # Each Bullet run had the time of its nscd partner's fall (the run of the same seed), not
        # its own time limit.
        fall = {r["seed"]: r["timing/stages/dynamic/simulated_time"] for r in mine if r["backend"] == "nscd"}
        given = {r["seed"]: r["timing/stages/dynamic/simulated_time"] for r in mine if r["backend"] == "bullet"}
        own = values(stopped, "bullet", "timing/stages/dynamic/simulated_time")
        assert given.keys() == fall.keys() and len(given) == 2
        assert all(given[s] == pytest.approx(fall[s], abs=0.01) == pytest.approx(3, abs=0.01) for s in given)
        assert own and all(t == pytest.approx(2, abs=0.01) for t in own)
        spans.append(f"{width}: 3")
    assert times == "Bullet's time at nscd's [t0]: " + "; ".join(spans)


def test_equal_time_without_a_settle_leaves_the_at_rest_column_empty(equal_time_sweep, settle_sweep):
    # SETTLED may be a report without bullet_settled (the study's own tables, docs/medium): Bullet at
    # its own limit is read from it and the at-rest column says it has nothing.
    sweep, report = equal_time_sweep
    _, settled_report = settle_sweep
    from_full = printed_lines("equal_time_table", sweep, report, settled_report, "MSP")
    # The equal-time report has no bullet_settled: as SETTLED it gives '-' at rest, and its own
    # Bullet runs (at nscd's time) in the 20 t0 column.
    lines = printed_lines("equal_time_table", sweep, report, report, "MSP")
    for line, full in zip(lines[:-1], from_full[:-1]):
        row, full_row = cells(line), cells(full)
        assert row[7] == "-" and full_row[7] != "-"
        assert row[2] == row[3] and row[5] == row[6]
        assert row[1] == full_row[1] and row[3:5] == full_row[3:5] and row[8] == full_row[8]
