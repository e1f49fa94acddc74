"""confpack from Python: packings as numpy arrays, and the deposition, the compactions and the
analysis of the C++ library (README, "Python").

    import confpack
    packing = confpack.read_packing("run/packing.json")      # grains and contacts as arrays
    result = confpack.run({"box": {"width": 4}}, backend="nscd")   # the dict of result.json
    result["solid_fraction"], result["profiles"]["phi_y"]["phi"]

A configuration is a dict laid out as config.json (keys box, population, deposition, compaction,
backend, backend_options, seed, threads; missing keys take their defaults, unknown keys are
refused). Bad input raises ValueError with the message `confpack` prints after "error: "; nothing
is ever written but by Packing.write. Ctrl-C stops a run at its next progress point
(KeyboardInterrupt).
"""
import json

from . import _confpack
from ._confpack import Box, Contacts, Packing, read_packing, __version__, __revision__

__all__ = ["Box", "Contacts", "Packing", "read_packing", "default_config", "resolve_config", "deposit",
           "run", "analyze", "study", "__version__",
           "__revision__"]


def _config_text(config):
    """config.json text of a dict (None: every default). numpy scalars count as numbers."""
    if config is None:
        config = {}
    if not isinstance(config, dict):
        raise TypeError(f"config: expected a dict laid out as config.json (got {type(config).__name__})")

    def plain(value):
        if hasattr(value, "item"):  # a numpy scalar
            return value.item()
        raise TypeError(f"config: {type(value).__name__} is not a JSON value")

    return json.dumps(config, default=plain, allow_nan=False)


def default_config():
    """The default configuration, as config.json."""
    return json.loads(_confpack._default_config())


def resolve_config(config=None, backend=None):
    """The fully resolved configuration of `config` (what config.json of its run holds);
    ValueError for a bad field."""
    return json.loads(_confpack._resolve_config(_config_text(config), backend))


def deposit(config=None, progress=None):
    """The geometric deposition of `config` (docs/model.md, "Deposition"): a Packing without
    contacts, the same as packing.json of `confpack deposit` with the same configuration.
    progress(fraction, status) is called now and then."""
    return _confpack._deposit(_config_text(config), progress)


def run(config=None, backend=None, progress=None):
    """Deposit, compact with `backend` ("nscd" or "bullet"; default: the configuration's) until
    equilibrium or the time limit, and analyse, as `confpack run` does, writing nothing.

    Returns the dict of result.json, plus "profiles" ({csv stem: {column: array}}, the CSV
    files of a run) and "packing" (the final Packing with its contacts and forces).
    progress(fraction, status) is called at every equilibrium check."""
    text, profiles, packing = _confpack._run(_config_text(config), backend, progress)
    result = json.loads(text)
    result["profiles"] = profiles
    result["packing"] = packing
    return result


def analyze(packing, allow_implausible=False, **options):
    """Every measurement of `confpack analyze` on a Packing: the dict of its result.json blocks
    plus "profiles". Options as the command's flags: margin, surface_cell, slice, lattice_cell,
    lattice (False: --no-lattice), force_threshold, gap_tolerance, inflate (--inflate S: every
    grain scaled by S) and type_band (--type-band B: coordination_band, 0 for none). An
    implausible packing raises ValueError unless allow_implausible."""
    text, profiles = _confpack._analyze(packing, allow_implausible, **options)
    result = json.loads(text)
    result["profiles"] = profiles
    return result


from . import study  # noqa: E402  (uses the names above)
