"""confpack.analyze gives the numbers `confpack analyze` writes: result.json's blocks and the CSV
profiles, to the last bit."""
import json

import numpy as np
import pytest

import confpack
from conftest import run_cli

PROFILES = ["phi_y", "z_y", "homogeneity_z", "homogeneity_y", "orientation_cos", "orientation_azimuth"]


def read_csv(path):
    """{column: array} of a profile CSV (comment lines start with '#')."""
    lines = [line for line in path.read_text().splitlines() if not line.startswith("#")]
    names = lines[0].split(",")
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    columns = np.array(rows, dtype=float).reshape(len(rows), len(names)).T
    return dict(zip(names, columns))


def assert_same_profiles(profiles, folder):
    assert sorted(profiles) == sorted(PROFILES)
    for stem in PROFILES:
        expected = read_csv(folder / f"{stem}.csv")
        assert list(profiles[stem]) == list(expected), stem
        for column, values in expected.items():
            assert np.array_equal(profiles[stem][column], values), (stem, column)


def assert_same_blocks(result, cli_result):
    """Every block confpack.analyze returns (all but the profiles) equals the CLI's."""
    blocks = {k: v for k, v in result.items() if k != "profiles"}
    assert blocks, "no result blocks"
    for key, value in blocks.items():
        assert value == cli_result[key], key


@pytest.mark.parametrize("which", ["run", "deposit"])
def test_analyze_equals_the_cli(which, cli, cli_run, cli_deposit, tmp_path):
    # A run's packing carries contacts and forces; a deposit's has none (geometric contacts).
    source = cli_run[1] / "packing.json" if which == "run" else cli_deposit / "packing.json"
    run_cli(cli, "analyze", source, "--out", tmp_path / "cli", "-q")
    cli_result = json.loads((tmp_path / "cli" / "result.json").read_text())
    result = confpack.analyze(confpack.read_packing(source))
    assert_same_blocks(result, cli_result)
    assert_same_profiles(result["profiles"], tmp_path / "cli")
    assert result["n_grains"] == len(confpack.read_packing(source))


def test_analyze_options_are_the_flags(cli, cli_run, tmp_path):
    source = cli_run[1] / "packing.json"
    run_cli(cli, "analyze", source, "--out", tmp_path / "cli", "-q", "--slice", "0.25", "--margin", "0.5",
            "--no-lattice", "--force-threshold", "0.1")
    cli_result = json.loads((tmp_path / "cli" / "result.json").read_text())
    result = confpack.analyze(confpack.read_packing(source), slice=0.25, margin=0.5, lattice=False,
                              force_threshold=0.1)
    assert_same_blocks(result, cli_result)
    assert_same_profiles(result["profiles"], tmp_path / "cli")


def test_the_published_readings_are_the_flags(cli, cli_run, tmp_path):
    # --inflate and --type-band: the inflated grains' numbers and the band's contact types.
    source = cli_run[1] / "packing.json"
    run_cli(cli, "analyze", source, "--out", tmp_path / "cli", "-q", "--inflate", "1.02", "--type-band", "0.05")
    cli_result = json.loads((tmp_path / "cli" / "result.json").read_text())
    result = confpack.analyze(confpack.read_packing(source), inflate=1.02, type_band=0.05)
    assert_same_blocks(result, cli_result)
    assert result["inflate"] == 1.02
    assert "coordination_band" in result
    # Grains scaled by 1.02 take 1.02^3 of the volume: the bulk's solid fraction grows by about that
    # factor (not exactly: the bulk region follows the free surface, which the inflation raises).
    plain = confpack.analyze(confpack.read_packing(source))
    assert result["solid_fraction"] == pytest.approx(1.02 ** 3 * plain["solid_fraction"], rel=5e-3)
    assert result["solid_fraction"] != pytest.approx(plain["solid_fraction"], rel=1e-2)


def test_a_bad_inflation_is_refused_with_the_flags_message(cli, cli_run):
    with pytest.raises(ValueError, match="inflat"):
        confpack.analyze(confpack.read_packing(cli_run[1] / "packing.json"), inflate=0.9)
