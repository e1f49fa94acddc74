"""Packings: the arrays say what the file says, and writing gives back the file the CLI wrote,
byte for byte."""
import json

import numpy as np
import pytest

import confpack


def grains_of(path):
    return json.loads(path.read_text())["grains"]


@pytest.mark.parametrize("which", ["cli_deposit", "pinacoid_deposit"])
def test_deposit_file_round_trip(which, request, tmp_path):
    source = request.getfixturevalue(which) / "packing.json"
    packing = confpack.read_packing(source)
    packing.write(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_bytes() == source.read_bytes()
    assert packing.contacts is None
    assert packing.source == str(source)


def test_run_file_round_trip(cli_run, tmp_path):
    _, out = cli_run
    packing = confpack.read_packing(out / "packing.json")
    packing.write(tmp_path / "again.json")
    assert (tmp_path / "again.json").read_bytes() == (out / "packing.json").read_bytes()
    assert len(packing.contacts) > 0


def test_arrays_match_the_file(cli_run):
    _, out = cli_run
    doc = json.loads((out / "packing.json").read_text())
    packing = confpack.read_packing(out / "packing.json")
    n = len(doc["grains"])
    assert len(packing) == n
    assert packing.positions.shape == (n, 3) and packing.orientations.shape == (n, 4)
    assert np.array_equal(packing.positions, [g["position"] for g in doc["grains"]])
    assert np.array_equal(packing.orientations, [g["orientation"] for g in doc["grains"]])
    assert np.array_equal(packing.sizes, [g["size"] for g in doc["grains"]])
    assert list(packing.shapes) == [g["shape"] for g in doc["grains"]]
    box = packing.box
    assert (box.length_x, box.width, box.periodic_y) == (doc["box"]["length_x"], doc["box"]["width"], False)
    c = packing.contacts
    assert np.array_equal(c.a, [k["a"] for k in doc["contacts"]])
    assert np.array_equal(c.b, [k["b"] for k in doc["contacts"]])
    assert list(c.types) == [k["type"] for k in doc["contacts"]]
    assert np.array_equal(c.normals, [k["normal"] for k in doc["contacts"]])
    assert np.array_equal(c.points, [p for k in doc["contacts"] for p in k["points"]])
    assert np.array_equal(c.point_forces, [f for k in doc["contacts"] for f in k["point_forces"]])
    assert np.allclose(c.normal_forces, [k["normal_force"] for k in doc["contacts"]], rtol=1e-15, atol=0)
    assert c.point_offsets[-1] == len(c.points)


def test_positions_and_sizes_are_read_only_views(cli_deposit):
    packing = confpack.read_packing(cli_deposit / "packing.json")
    positions = packing.positions
    assert not positions.flags.writeable and not packing.sizes.flags.writeable
    assert np.shares_memory(positions, packing.positions)  # no copy: the same grains
    with pytest.raises(ValueError):
        positions[0, 0] = 1.0
    del packing  # the view keeps the packing alive
    assert np.isfinite(positions).all()


def test_packing_from_arrays_writes_the_same_file(cli_run, tmp_path):
    _, out = cli_run
    p = confpack.read_packing(out / "packing.json")
    c = p.contacts
    contacts = confpack.Contacts(c.a, c.b, c.normals, c.points, point_offsets=c.point_offsets, types=c.types,
                                 point_forces=c.point_forces, point_gaps=c.point_gaps,
                                 point_tangent_forces=c.point_tangent_forces)
    b = p.box
    box = confpack.Box(length_x=b.length_x, width=b.width, periodic_y=b.periodic_y, height=b.height)
    rebuilt = confpack.Packing(box, p.positions, p.sizes, orientations=p.orientations, shapes=p.shapes,
                               contacts=contacts, wall_friction=p.wall_friction)
    rebuilt.write(tmp_path / "rebuilt.json")
    assert (tmp_path / "rebuilt.json").read_bytes() == (out / "packing.json").read_bytes()


def test_pinacoid_params(pinacoid_deposit, tmp_path):
    p = confpack.read_packing(pinacoid_deposit / "packing.json")
    assert set(p.shapes) == {"pinacoid"}
    assert np.array_equal(p.pinacoid_params, [[g["params"]["G"], g["params"]["E"], g["params"]["alpha_deg"]]
                                              for g in grains_of(pinacoid_deposit / "packing.json")])
    rebuilt = confpack.Packing(p.box, p.positions, p.sizes, orientations=p.orientations, shapes=p.shapes,
                               pinacoid_params=p.pinacoid_params)
    rebuilt.write(tmp_path / "rebuilt.json")
    assert (tmp_path / "rebuilt.json").read_bytes() == (pinacoid_deposit / "packing.json").read_bytes()
