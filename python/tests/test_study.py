"""confpack.study.load reads a sweep folder that `confpack sweep` wrote: one row per run with its
configuration and every number of its result.json."""
import json

import numpy as np
import pytest

import confpack
from conftest import cli_error, run_cli

SWEEP = {
    "format": "confpack-sweep", "version": 1, "name": "tiny",
    "base": {"box": {"length_x": 3, "height": 7}, "compaction": {"time_limit": 2}},
    "biperiodic_width": 3,
    "vary": {"width": [3, 4, "biperiodic"], "backend": ["nscd"], "seed": [1]},
}


@pytest.fixture(scope="module")
def sweep_dir(cli, tmp_path_factory):
    folder = tmp_path_factory.mktemp("sweep")
    (folder / "tiny.json").write_text(json.dumps(SWEEP))
    run_cli(cli, "sweep", folder / "tiny.json", "--out", folder / "study", "-q")
    return folder / "study"


def test_rows(sweep_dir):
    rows = confpack.study.load(sweep_dir, details=True)
    assert [r["run"] for r in rows] == ["r0000", "r0001", "r0002"]
    assert [(r["W"], r["biperiodic"]) for r in rows] == [(3, False), (4, False), (3, True)]
    for r in rows:
        result = json.loads((sweep_dir / "runs" / r["run"] / "result.json").read_text())
        assert r["status"] == "done" and r["error"] is None
        assert r["result"] == result
        assert r["solid_fraction"] == result["solid_fraction"]
        assert r["coordination/Z"] == result["coordination"]["Z"]
        assert r["config"] == json.loads((sweep_dir / "runs" / r["run"] / "config.json").read_text())
        assert (r["shape"], r["x_S"], r["mu_w"], r["seed"], r["backend"], r["family"]) == \
            ("sphere", 0, 0, 1, "nscd", "MSP")


def test_array_plots_in_three_lines(sweep_dir):
    runs = confpack.study.load(sweep_dir, array=True)
    walls = runs[(runs["status"] == "done") & ~runs["biperiodic"]]
    x, phi = 1 / walls["W"], walls["solid_fraction"]
    assert np.allclose(x, [1 / 3, 1 / 4])
    rows = confpack.study.load(sweep_dir)
    assert list(phi) == [rows[0]["solid_fraction"], rows[1]["solid_fraction"]]
    # profile_fit needs side walls: NaN, not a number, for the biperiodic run.
    assert runs["biperiodic"].tolist() == [False, False, True]
    assert runs.dtype["seed"] == np.uint64 and runs.dtype["run"].kind == "U"


def test_unfinished_runs_are_listed(sweep_dir, tmp_path):
    # A sweep file whose runs never ran: every run is there, pending, with no result.
    folder = tmp_path / "pending"
    (tmp_path / "tiny.json").write_text(json.dumps(SWEEP))
    (folder).mkdir()
    (folder / "sweep.json").write_bytes((sweep_dir / "sweep.json").read_bytes())
    rows = confpack.study.load(folder, details=True)
    assert [r["status"] for r in rows] == ["pending"] * 3
    assert all(r["result"] is None and "solid_fraction" not in r for r in rows)
    table = confpack.study.load(folder, array=True)
    assert len(table) == 3 and set(table["status"]) == {"pending"}


def test_not_a_sweep(cli, tmp_path):
    message = cli_error(cli, "report", tmp_path)
    with pytest.raises(ValueError) as caught:
        confpack.study.load(tmp_path)
    assert str(caught.value) == message
