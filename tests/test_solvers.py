"""Secant iteration control: stall detection, and a clear stop where large friction makes the modified
method oscillate."""
import json

from mpi4py import MPI

from forming_fenicsx.cli import main
from forming_fenicsx.solvers import stalled

from test_drawing import DEMOS


def test_stalled():
    assert not stalled([1.0, 0.5, 0.25, 0.1], window=2)
    assert stalled([1.0, 0.1, 0.5, 0.2], window=2)
    assert stalled([1.0, 0.5, 0.8, 0.5, 0.8], window=3)
    assert not stalled([1.0, 0.5], window=3)


def test_large_friction_oscillation_stops_with_a_clear_message(shared_tmp, capsys):
    out = shared_tmp / "mu1"
    code = main(["run", str(DEMOS / "example2_drawing.toml"), "--out", str(out), "--quiet", "--set", "friction.mu=1.0",
                 "--set", "discretisation.mesh_size=0.15", "--set", "output.fields=false",
                 "--set", "output.figures=false"])
    MPI.COMM_WORLD.barrier()
    assert code == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert "oscillates" in summary["reason"] and "not be unique" in summary["reason"]
    assert summary["outer_iterations"] < summary["scene"]["solver"]["max_outer_iterations"]
    assert (out / "history.csv").exists()
