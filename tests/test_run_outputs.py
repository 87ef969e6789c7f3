"""`forming run`: the files of a run, their keys and contents, and a run that does not converge."""
import csv
import json
import xml.etree.ElementTree as ElementTree
from pathlib import Path

from mpi4py import MPI

from forming_fenicsx.cli import main

DEMO = str(Path(__file__).parents[1] / "demos" / "example1_extrusion.toml")
COARSE = ["--set", "discretisation.mesh_size=1.0", "--quiet"]
REQUIRED = {"scene", "dolfinx_version", "mpi_ranks", "dofs", "converged", "linear_solves", "outer_iterations",
            "wall_time_s", "ram_pressure", "mean_hydrostatic_pressure", "die_force_x", "force_balance_residual"}


def test_run_writes_summary_history_fields_and_figures(shared_tmp):
    out = shared_tmp / "run"
    assert main(["run", DEMO, "--out", str(out), "--set", "friction.mu=0.1", *COARSE,
                 "--", "-ksp_type", "preonly"]) == 0
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert REQUIRED <= set(summary)
    assert summary["converged"] is True and summary["mpi_ranks"] == MPI.COMM_WORLD.size
    assert summary["scene"]["friction"]["mu"] == 0.1 and summary["scene"]["discretisation"]["mesh_size"] == 1.0
    assert summary["force_balance_residual"] < 1e-2
    with (out / "history.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == summary["linear_solves"]
    assert float(rows[-1]["relative_increment"]) < 1e-4
    assert [int(r["outer"]) for r in rows][-1] == summary["outer_iterations"] - 1
    names = {a.get("Name") for a in ElementTree.parse(out / "fields.xdmf").iter("Attribute")}
    assert names == {"velocity", "equivalent_strain_rate", "hydrostatic_pressure", "secant_viscosity"}
    assert (out / "fields.h5").stat().st_size > 1000
    for figure in ("velocity.png", "strain_rate.png"):
        assert (out / figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_not_converged_exits_non_zero_and_keeps_last_iterate(shared_tmp, capsys):
    out = shared_tmp / "short"
    assert main(["run", DEMO, "--out", str(out), "--set", "solver.max_iterations=3", *COARSE]) == 3
    MPI.COMM_WORLD.barrier()
    if MPI.COMM_WORLD.rank == 0:
        assert "not converged" in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and "3 iterations" in summary["reason"]
    assert summary["linear_solves"] == 4
    assert (out / "fields.xdmf").exists()
