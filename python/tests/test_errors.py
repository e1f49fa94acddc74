"""Every bad input raises the exception of its kind with the message `confpack` prints after
"error: ", and nothing is written."""
import json
import os

import numpy as np
import pytest

import confpack
from conftest import TINY, TINY_CONFIG, cli_error


@pytest.fixture
def bad_packing(cli_deposit, tmp_path):
    """Writes a copy of the tiny deposit changed by `change(doc)` and returns its path."""

    def make(change, name="bad.json"):
        doc = json.loads((cli_deposit / "packing.json").read_text())
        change(doc)
        path = tmp_path / name
        path.write_text(json.dumps(doc))
        return path

    return make


def set_size(doc, value):
    doc["grains"][2]["size"] = value


def test_unreadable_and_malformed_packing_files(cli, bad_packing, tmp_path):
    cases = [
        tmp_path / "missing.json",
        tmp_path,  # a folder
        bad_packing(lambda d: set_size(d, -1.0)),
        bad_packing(lambda d: d.update(extra=1), "extra.json"),
        bad_packing(lambda d: d["grains"][0].update(shape="cube"), "cube.json"),
    ]
    (tmp_path / "text.json").write_text("{ not json")
    cases.append(tmp_path / "text.json")
    for path in cases:
        message = cli_error(cli, "analyze", path, "--out", tmp_path / "out")
        with pytest.raises(ValueError) as caught:
            confpack.read_packing(path)
        assert str(caught.value) == message
    assert not (tmp_path / "out").exists()


def test_implausible_packing(cli, bad_packing, tmp_path):
    path = bad_packing(lambda d: set_size(d, 2.9), "implausible.json")  # overlaps its neighbours
    message = cli_error(cli, "analyze", path, "--out", tmp_path / "out")
    packing = confpack.read_packing(path)
    with pytest.raises(ValueError) as caught:
        confpack.analyze(packing)
    assert str(caught.value) == message
    assert "implausible packing" in message
    assert confpack.analyze(packing, allow_implausible=True)["n_grains"] == len(packing)


def test_backend_options(cli, tmp_path):
    message = cli_error(cli, "run", *TINY, "--backend-options", '{"tolerence": 1e-6}', "--out", tmp_path / "out")
    with pytest.raises(ValueError) as caught:
        confpack.run({**TINY_CONFIG, "backend_options": {"tolerence": 1e-6}})
    assert str(caught.value) == message
    assert not (tmp_path / "out").exists()


def test_too_many_grains(cli, tmp_path):
    message = cli_error(cli, "deposit", *TINY, "--max-grains", "10", "--out", tmp_path / "out")
    for call in (confpack.deposit, confpack.run):
        with pytest.raises(ValueError) as caught:
            call({**TINY_CONFIG, "deposition": {"max_grains": 10}})
        assert str(caught.value) == message


@pytest.mark.parametrize("config", [
    {"box": {"width": -1}},
    {"box": {"width": "wide"}},
    {"compaction": {"time_limit": 0}},
    {"compaction": {"protocol": "slow"}},
    {"population": {"shape": "cube"}},
    {"backend": "lmgc90"},
    {"seed": -1},
])
def test_bad_configuration_fields(cli, config, tmp_path):
    # The command line's flags cannot express these (its parser refuses them first); a sweep file's
    # base goes through the same reader, and `confpack sweep` ends its line with the same message.
    (tmp_path / "sweep.json").write_text(json.dumps({"base": config, "vary": {"seed": [1]}}))
    line = cli_error(cli, "sweep", tmp_path / "sweep.json", "--out", tmp_path / "out")
    for call in (confpack.resolve_config, confpack.deposit, confpack.run):
        with pytest.raises(ValueError) as caught:
            call(config)
        assert line.endswith(": " + str(caught.value)), (line, str(caught.value))
    assert not (tmp_path / "out").exists()


def test_unknown_configuration_key():
    with pytest.raises(ValueError, match=r"^config\.boxx: unknown key \(known: box, walls, population, "):
        confpack.deposit({"boxx": {}})


def test_bad_backend_argument():
    with pytest.raises(ValueError, match="unknown backend 'yade'"):
        confpack.run(TINY_CONFIG, backend="yade")


def test_not_a_configuration():
    with pytest.raises(TypeError):
        confpack.deposit([("box", {})])
    with pytest.raises(TypeError):
        confpack.deposit({"box": {"width": object()}})
    with pytest.raises(ValueError):
        confpack.deposit({"box": {"width": float("nan")}})


def test_bad_arrays():
    box = confpack.Box(length_x=3, width=3, height=3)
    with pytest.raises(ValueError, match=r"positions: expected shape"):
        confpack.Packing(box, np.zeros((4, 2)), np.ones(4))
    with pytest.raises(ValueError, match=r"sizes: expected shape \(2,\)"):
        confpack.Packing(box, [[1, 1, 1], [2, 2, 2]], np.ones(3))
    with pytest.raises(ValueError, match=r"grains\[1\]\.size"):  # the packing file's own rule
        confpack.Packing(box, [[1, 1, 1], [2, 2, 2]], [1.0, -1.0])
    with pytest.raises(ValueError, match=r"orientation: must be a unit quaternion"):
        confpack.Packing(box, [[1, 1, 1]], [1.0], orientations=[[2.0, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"unknown shape 'cube'"):
        confpack.Packing(box, [[1, 1, 1]], [1.0], shapes=["cube"])
    with pytest.raises(ValueError):
        confpack.Box(width=-1)


def test_nothing_written_on_failure(tmp_path, bad_packing, monkeypatch):
    implausible = confpack.read_packing(bad_packing(lambda d: set_size(d, 2.9)))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    with pytest.raises(ValueError):
        confpack.run({**TINY_CONFIG, "compaction": {"time_limit": -1}})
    with pytest.raises(ValueError):
        confpack.analyze(implausible)
    with pytest.raises(RuntimeError):
        implausible.write(work / "no-such-folder" / "packing.json")
    assert os.listdir(work) == []
