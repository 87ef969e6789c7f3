"""`forming study`: the grid, errors against the exact value or a Richardson extrapolation, costs, the
Pareto plot, and a restarted study that skips the runs it has."""
import csv
import json
import math
from pathlib import Path

import pytest
from mpi4py import MPI

import forming_fenicsx.study as study
from forming_fenicsx.cli import main
from forming_fenicsx.errors import SceneError
from forming_fenicsx.scene import read_scene_data

DEMO = str(Path(__file__).parents[1] / "demos" / "example1_extrusion.toml")
SIZES = "discretisation.mesh_size=1.0,0.5,0.25"


def test_study_against_hill_and_resumption(shared_tmp, monkeypatch):
    out = shared_tmp / "study"
    assert main(["study", DEMO, "--vary", SIZES, "--vary", "solver.method=direct,modified", "--out", str(out),
                 "--quiet", "--set", "solver.tolerance=1e-3"]) == 0
    MPI.COMM_WORLD.barrier()
    with (out / "study.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == 6 and {r["solver.method"] for r in rows} == {"direct", "modified"}
    hill = 1 + math.pi / 2
    for row in rows:
        assert row["reference_kind"] == "exact" and float(row["reference"]) == pytest.approx(hill, rel=1e-12)
        assert float(row["relative_error"]) == pytest.approx(abs(float(row["ram_pressure"]) / hill - 1), rel=1e-12)
        assert int(row["linear_solves"]) > 0 and float(row["wall_time_s"]) > 0 and int(row["dofs"]) > 0
    errors = [float(r["relative_error"]) for r in rows if r["solver.method"] == "direct"]
    assert errors[0] > errors[1] > errors[2]
    assert (out / "pareto.png").read_bytes()[:4] == b"\x89PNG"
    # started again: every run is in study.json, nothing is solved
    calls = []
    monkeypatch.setattr(study, "solve_scene", lambda *a, **k: calls.append(a) or pytest.fail("solved again"))
    again = study.run_study(read_scene_data(DEMO, ["solver.tolerance=1e-3"]),
                            [SIZES, "solver.method=direct,modified"], out)
    assert not calls and len(again) == 6


def test_study_richardson_reference(shared_tmp):
    out = shared_tmp / "richardson"
    rows = study.run_study(read_scene_data(DEMO, ["solver.method=direct"]), [SIZES], out, quantity="die_force_x")
    limit = rows[0]["reference"]
    assert rows[0]["reference_kind"].startswith("richardson")
    forces = [r["die_force_x"] for r in rows]
    assert forces[0] > forces[1] > forces[2] > limit  # converging from above to the extrapolated value
    MPI.COMM_WORLD.barrier()
    assert json.loads((out / "study.json").read_text())["quantity"] == "die_force_x"


def test_bad_vary_is_a_scene_error():
    with pytest.raises(SceneError):
        study.parse_vary(["discretisation.mesh_size=1.0,,0.5"])
    with pytest.raises(SceneError):
        study.run_study(read_scene_data(DEMO), ["penalty.d=0.001,-1"], Path("/nonexistent/never"))
