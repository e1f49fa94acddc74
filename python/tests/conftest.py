"""Shared fixtures: the `confpack` command line next to the module (the same build), and tiny runs
it made, against which the module is compared. Every pile here is a few dozen grains with a time
limit of a fraction of t0, so that the whole suite takes seconds.

The module must import: a missing or broken build fails the suite, it never skips it."""
import os
import pathlib
import subprocess

import pytest

import confpack

# A 3 x 3 x 7 box holds 73 grains of d_L = 1 at phi = 0.6, the lowest box with a bulk region
# (3 d_L from the floor and from the surface); in 4 t0 (some 1,300 steps, a fraction of a second)
# the pile has fallen and carries forces, though not at rest.
TINY = ["--length-x", "3", "--width", "3", "--height", "7", "--seed", "3"]
TINY_CONFIG = {"box": {"length_x": 3, "width": 3, "height": 7}, "seed": 3}
TIME_LIMIT = 4.0


def _find_cli():
    if "CONFPACK_CLI" in os.environ:
        return pathlib.Path(os.environ["CONFPACK_CLI"])
    # The build tree: build/python/confpack/__init__.py -> build/apps/confpack.
    return pathlib.Path(confpack.__file__).resolve().parents[2] / "apps" / "confpack"


CLI = _find_cli()


@pytest.fixture(scope="session")
def cli():
    if not CLI.is_file():
        pytest.fail(f"the confpack command line is not at {CLI} (set CONFPACK_CLI)")
    return CLI


def run_cli(cli, *args, check=True):
    done = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True)
    if check and done.returncode != 0:
        raise AssertionError(f"confpack {' '.join(map(str, args))} failed ({done.returncode}): {done.stderr}")
    return done


def cli_error(cli, *args, code=2):
    """The message of a command that must fail with `code`: its one stderr line after "error: "."""
    done = run_cli(cli, *args, check=False)
    assert done.returncode == code, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    return lines[0].split(": error: ", 1)[1]


@pytest.fixture(scope="session")
def cli_deposit(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "deposit"
    run_cli(cli, "deposit", *TINY, "--out", out, "-q")
    return out


@pytest.fixture(scope="session", params=["nscd", "bullet"])
def cli_run(request, cli, tmp_path_factory):
    """`confpack run` of the tiny pile with each backend: (backend, output folder)."""
    backend = request.param
    out = tmp_path_factory.mktemp("cli") / f"run-{backend}"
    run_cli(cli, "run", *TINY, "--backend", backend, "--time-limit", TIME_LIMIT, "--out", out, "-q")
    return backend, out


@pytest.fixture(scope="session")
def pinacoid_deposit(cli, tmp_path_factory):
    out = tmp_path_factory.mktemp("cli") / "pinacoids"
    run_cli(cli, "deposit", *TINY, "--shape", "pinacoid", "--out", out, "-q")
    return out
