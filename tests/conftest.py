"""Shared fixtures; every test runs serially and under ``mpirun -n 2 python -m mpi4py -m pytest``."""
from __future__ import annotations

import json
from pathlib import Path

import pytest
from mpi4py import MPI

from forming_fenicsx.scene import Scene, scene_from_dict


@pytest.fixture
def shared_tmp(tmp_path: Path) -> Path:
    """A temporary folder that every rank sees (rank 0's)."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


def make_scene(**sections) -> Scene:
    """An extrusion scene with the given section overrides, e.g. make_scene(friction={"mu": 0.1})."""
    data = {"process": {"kind": "extrusion"}, "output": {"fields": False, "figures": False}}
    for name, values in sections.items():
        data.setdefault(name, {}).update(values)
    return scene_from_dict(data)


# Example 1 on a coarse mesh (h = 0.5, grading 8): about a second per solve.
COARSE = {"mesh_size": 0.5, "corner_grading": 8.0}
_solved: dict[str, dict] = {}


def solved(**sections) -> dict:
    """Summary of Example 1 on the coarse mesh with the given section overrides, solved once per session."""
    from forming_fenicsx.run import solve_scene

    sections["discretisation"] = {**COARSE, **sections.get("discretisation", {})}
    key = json.dumps(sections, sort_keys=True)
    if key not in _solved:
        _solved[key] = solve_scene(make_scene(**sections))[2]
    return _solved[key]
