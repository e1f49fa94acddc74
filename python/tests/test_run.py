"""deposit, run and the configuration from Python equal the command line's for the same seed;
progress calls back, and Ctrl-C (SIGINT) stops a run with KeyboardInterrupt."""
import json
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import confpack
from conftest import TIME_LIMIT, TINY, TINY_CONFIG, run_cli
from test_analyze import assert_same_profiles


def tiny(**compaction):
    return {**TINY_CONFIG, "compaction": {"time_limit": TIME_LIMIT, **compaction}}


def test_deposit_equals_the_cli(cli_deposit, tmp_path):
    packing = confpack.deposit(TINY_CONFIG)
    packing.write(tmp_path / "packing.json")
    assert (tmp_path / "packing.json").read_bytes() == (cli_deposit / "packing.json").read_bytes()
    assert confpack.resolve_config(TINY_CONFIG) == json.loads((cli_deposit / "config.json").read_text())


def test_default_config_is_resolved():
    config = confpack.default_config()
    assert config == confpack.resolve_config({}) == confpack.resolve_config(None)
    assert set(config) == {"box", "walls", "population", "deposition", "compaction", "backend", "backend_options", "seed",
                           "threads"}


def test_run_equals_the_cli(cli_run, tmp_path):
    backend, out = cli_run
    calls = []
    result = confpack.run(tiny(), backend=backend, progress=lambda fraction, status: calls.append((fraction, status)))
    # The same final packing, byte for byte, and the same numbers.
    result["packing"].write(tmp_path / "packing.json")
    assert (tmp_path / "packing.json").read_bytes() == (out / "packing.json").read_bytes()
    cli_result = json.loads((out / "result.json").read_text())
    assert_same_profiles(result.pop("profiles"), out)
    result.pop("packing")
    assert set(result) == set(cli_result)
    for key in result:
        if key != "timing":  # wall times differ from run to run
            assert result[key] == cli_result[key], key
    assert result["timing"]["steps"] == cli_result["timing"]["steps"]
    assert result["config"]["backend"] == backend
    # Both record the build: the module is the same library as the command line.
    assert (result["confpack_version"], result["confpack_revision"]) == (confpack.__version__, confpack.__revision__)
    assert calls and all(0.0 <= f <= 1.0 and isinstance(s, str) for f, s in calls)


@pytest.fixture
def ctrl_c_raises():
    """Python's own SIGINT handler, which it leaves out when started with SIGINT ignored (a suite
    run in the background by a shell without job control, or under nohup)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_a_run(ctrl_c_raises):
    def interrupt(fraction, status):
        os.kill(os.getpid(), signal.SIGINT)  # what Ctrl-C in a terminal or a notebook does

    with pytest.raises(KeyboardInterrupt):
        confpack.run(tiny(check_interval=10), progress=interrupt)
    # The module is usable after the interruption.
    assert confpack.run(tiny(), backend="bullet")["n_grains"] > 0


def test_an_error_in_the_callback_stops_the_run():
    class Stop(Exception):
        pass

    def fail(fraction, status):
        raise Stop(status)

    with pytest.raises(Stop):
        confpack.run(tiny(), progress=fail)
    with pytest.raises(Stop):
        confpack.deposit(TINY_CONFIG, progress=fail)


def test_numpy_scalars_are_numbers():
    config = {"box": {"length_x": np.float64(3), "width": np.int64(3), "height": 7.0}, "seed": np.uint64(3)}
    assert confpack.resolve_config(config) == confpack.resolve_config(TINY_CONFIG)


def test_ctrl_c_from_outside_stops_the_compaction(tmp_path):
    # A real SIGINT while the compaction runs in C++ without the GIL and without a callback: the
    # run stops at its next equilibrium check, long before its 400 t0.
    script = (
        "import signal, sys, confpack\n"
        # Python's handler even if this suite was started with SIGINT ignored (the child inherits it).
        "signal.signal(signal.SIGINT, signal.default_int_handler)\n"
        f"config = {{**{TINY_CONFIG!r}, 'compaction': {{'time_limit': 400}}}}\n"
        "print('started', flush=True)\n"
        "try:\n"
        "    confpack.run(config)\n"
        "except KeyboardInterrupt:\n"
        "    print('interrupted', flush=True)\n"
        "    sys.exit(3)\n"
    )
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True,
                             env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert child.stdout.readline().strip() == "started"
    time.sleep(0.5)  # into the compaction
    start = time.monotonic()
    child.send_signal(signal.SIGINT)
    out, _ = child.communicate(timeout=30)
    assert child.returncode == 3 and out.strip() == "interrupted"
    assert time.monotonic() - start < 5
