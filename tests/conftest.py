"""Shared fixtures; every test runs serially and under
``mpirun -n 2 python -m mpi4py -m pytest``."""
from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType

import pytest
from mpi4py import MPI

from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.config.scene import Scene


# The mark `no_parallel_content`: a test whose work does not depend on the number of ranks of the
# pytest run, because it is pure Python (scene validation, closed forms, the limit-analysis linear
# programs with scipy: nothing reads MPI.COMM_WORLD or builds a mesh) or because rank 0 launches a
# child process that is the same in both phases (a serial `forming run`, or the child's own
# `mpirun -n 2`). Under `mpirun -n 2` such a test would only repeat the serial phase's work on each
# rank, so the 2-rank phase of scripts/test deselects it (pytest's summary counts it as
# "deselected"); the serial phase runs it. Never put it on a test that solves, assembles or
# partitions anything in the pytest process: the 2-rank run is how parallel correctness is tested.
NO_PARALLEL_CONTENT = "no_parallel_content"


def pytest_configure(config):
    config.addinivalue_line("markers", f"{NO_PARALLEL_CONTENT}: the same serial work on any number "
                            "of ranks (pure Python or a child process): "
                            "run in the serial phase only")
    _remember_compiled_modules()


def _remember_compiled_modules() -> None:
    """FFCx finds a compiled form in its cache with an import finder that lists the whole cache
    folder at every dolfinx.fem.form call (15k files here: 10 ms a call, under mpirun rank 0 and
    then rank 1 in turn). The suite makes about 9700 such calls for 1500 distinct modules: 114 of
    its 290 s serially (measured). Keep each module found in this process and hand it out again:
    the same shared library, so the same forms. Modules still to be compiled are not kept, and
    the child processes of the tests (a cold cache among them) look up as usual."""
    import ffcx.codegeneration.jit as jit

    lookup = jit.get_cached_module
    found: dict[tuple[str, str], tuple] = {}

    def get_cached_module(module_name: str, object_names: list[str], cache_dir: Path,
                          timeout: int) -> tuple[list | None, ModuleType | None]:
        key = (module_name, str(cache_dir))
        if key not in found:
            objects, module = lookup(module_name, object_names, cache_dir, timeout)
            if objects is None:  # not in the cache: the caller compiles it
                return objects, module
            found[key] = objects, module
        objects, module = found[key]
        return list(objects), module  # a list of its own for each caller, as FFCx gives

    jit.get_cached_module = get_cached_module


def pytest_collection_modifyitems(config, items):
    if MPI.COMM_WORLD.size == 1:
        return
    dropped = [item for item in items if item.get_closest_marker(NO_PARALLEL_CONTENT)]
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = [item for item in items if not item.get_closest_marker(NO_PARALLEL_CONTENT)]


@contextmanager
def kept_figures() -> Iterator[dict]:
    """Every matplotlib figure saved inside the block, by file name (e.g. "velocity.png"), for a
    test to read its axes, titles and artists (rank 0 draws a run's figures)."""
    import matplotlib.figure

    saved = {}
    original = matplotlib.figure.Figure.savefig

    def keep(fig, path, **kwargs):
        saved[Path(path).name] = fig
        return original(fig, path, **kwargs)

    matplotlib.figure.Figure.savefig = keep
    try:
        yield saved
    finally:
        matplotlib.figure.Figure.savefig = original


@pytest.fixture
def shared_tmp(tmp_path: Path) -> Path:
    """A temporary folder that every rank sees (rank 0's)."""
    return Path(MPI.COMM_WORLD.bcast(str(tmp_path), root=0))


# The paper's absolute penalties of Examples 1 and 2 and its pure penalty contact, which the tests
# of the paper's examples were written for; a test that names a penalty (absolute or relative)
# replaces the paper's value.
PAPER_PENALTIES = {"extrusion": {"penalty": {"d": 1e-3, "d_N": 1e-6, "augmented": False},
                                 "friction": {"d_T": 1e-6}},
                   "drawing": {"penalty": {"d": 5e-3, "d_N": 1e-2, "augmented": False},
                               "friction": {"d_T": 1e-6}}}


def make_scene(**sections) -> Scene:
    """An extrusion scene with the given section overrides, e.g. make_scene(friction={"mu": 0.1}),
    and the paper's penalties unless a section names its own."""
    data = {"process": {"kind": "extrusion"}, "output": {"fields": False, "figures": False}}
    kind = sections.get("process", {}).get("kind", "extrusion")
    for name, values in PAPER_PENALTIES[kind].items():
        given = {key.removesuffix("_relative") for key in sections.get(name, {})}
        data[name] = {key: value for key, value in values.items() if key not in given}
    for name, values in sections.items():
        data.setdefault(name, {}).update(values)
    return scene_from_dict(data)


# Example 1 on a coarse mesh (h = 0.5, grading 8): about a second per solve.
COARSE = {"mesh_size": 0.5, "corner_grading": 8.0}
_solved: dict[str, dict] = {}


def solved(**sections) -> dict:
    """Summary of Example 1 on the coarse mesh with the given section overrides, solved once per
    session: overrides that resolve to the same scene (a value given at its default, e.g. d_T = 1e-6
    or the exit thickness 5) share one solve."""
    from forming_fenicsx.app.run import solve_scene

    sections["discretisation"] = {**COARSE, **sections.get("discretisation", {})}
    scene = make_scene(**sections)
    key = json.dumps(scene.to_dict(), sort_keys=True)
    if key not in _solved:
        _solved[key] = solve_scene(scene)[2]
    return _solved[key]
