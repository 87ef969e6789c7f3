"""FFCx's cached forms looked up by exact file name (core/jit_cache.py) while a command runs."""
import dolfinx.fem
import dolfinx.mesh
import ffcx.codegeneration.jit as ffcx_jit
import pytest
import ufl
from mpi4py import MPI

from forming_fenicsx.core import jit_cache
from forming_fenicsx.core.jit_cache import exact_lookup


def _area(comm: MPI.Comm, height: float) -> float:
    """The area of a 1 x height rectangle by a form compiled (or found in the cache) now."""
    mesh = dolfinx.mesh.create_rectangle(comm, [[0.0, 0.0], [1.0, height]], [3, 2],
                                         dolfinx.mesh.CellType.quadrilateral)
    one = dolfinx.fem.Constant(mesh, 1.0)
    return comm.allreduce(dolfinx.fem.assemble_scalar(
        dolfinx.fem.form(one * ufl.dx(domain=mesh))), op=MPI.SUM)


def test_forms_are_found_by_exact_name_and_ffcx_lookup_is_restored(monkeypatch):
    """Inside the block every lookup is jit_cache's and finds the compiled form (the area it
    assembles is right, from the cache: a form compiled before the block); after it, FFCx's own."""
    comm = MPI.COMM_WORLD
    original = ffcx_jit.get_cached_module
    assert _area(comm, 0.5) == pytest.approx(0.5, abs=1e-14)  # compiled or cached, FFCx's lookup
    found = []
    exact = jit_cache.get_cached_module

    def counted(*args, **kwargs):
        result = exact(*args, **kwargs)
        found.append(result[1] is not None)
        return result

    monkeypatch.setattr(jit_cache, "get_cached_module", counted)
    with exact_lookup():
        assert ffcx_jit.get_cached_module is counted
        assert _area(comm, 0.25) == pytest.approx(0.25, abs=1e-14)
    assert ffcx_jit.get_cached_module is original
    if comm.rank == 0:  # the rank that compiles; the others wait for it in dolfinx's mpi_jit
        assert found and all(found)
