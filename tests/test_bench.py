"""`forming bench`: each case in a child process under mpirun, a row per case with solves, the time
split, peak memory, the result and its comparison with the direct method."""
import json
import os
import subprocess
import sys

import pytest
from mpi4py import MPI

from forming_fenicsx.app.bench import compare, median_run, run_case
from forming_fenicsx.app.bench_free_surface import free_surface_bench, free_surface_table


def test_run_case_in_process_gives_a_full_row():
    row = run_case({"example": 1, "mesh_size": 1.0, "method": "newton"})
    assert row["converged"] and row["ranks"] == MPI.COMM_WORLD.size and row["linear_solves"] <= 15
    split = sum(row[f"{key}_s"] for key in ("setup", "assembly", "factorisation", "solve", "rest",
                                            "postprocess"))
    assert abs(split - row["wall_time_s"]) < 0.1 * row["wall_time_s"]  # the parts cover the run
    assert row["factorisation_s"] > 0 and row["peak_memory_mb"] > 50
    assert row["exact"] is not None and abs(row["value"] / row["exact"] - 1) < 0.2


@pytest.mark.no_parallel_content  # child processes under their own mpirun (tests/conftest.py)
def test_bench_command_launches_each_case_and_compares(shared_tmp):
    """The parent (outside any MPI job) launches the cases under mpirun and compares them."""
    out = shared_tmp / "bench.json"
    if MPI.COMM_WORLD.rank == 0:
        env = {k: v for k, v in os.environ.items()
               if not k.startswith(("OMPI_", "PMIX_", "PRTE_", "OPAL_"))}
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1",
                   PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")
        done = subprocess.run([sys.executable, "-m", "forming_fenicsx.app.cli", "bench",
                               "--examples", "1", "--sizes", "1.0", "--methods", "direct", "newton",
                               "--repeat", "2", "--out", str(out)],
                              capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        assert ("| example | h | ranks | symmetry | formulation | method | converged |"
                in done.stdout)
        order = [(line.split(":")[0], line.split(", ")[-2].split(":")[0])
                 for line in done.stdout.splitlines()
                 if line.startswith("run ")]  # rounds: every case once, then again
        assert order == [("run 1/2", "direct"), ("run 1/2", "newton"),
                         ("run 2/2", "direct"), ("run 2/2", "newton")]
    MPI.COMM_WORLD.barrier()
    rows = {r["method"]: r for r in json.loads(out.read_text())}
    assert rows["newton"]["linear_solves"] < rows["direct"]["linear_solves"]
    assert rows["newton"]["vs_direct"] < 1e-3 and rows["direct"]["vs_direct"] == 0
    for row in rows.values():  # two runs each, the faster kept (the lower middle of two)
        assert (len(row["wall_time_runs_s"]) == 2
                and row["wall_time_s"] == min(row["wall_time_runs_s"]))


def test_median_run_keeps_the_middle_run_and_every_time():
    runs = [{"wall_time_s": t, "linear_solves": n} for t, n in ((3.0, 7), (1.0, 8), (2.0, 9))]
    row = median_run(runs)
    assert (row["wall_time_s"] == 2.0 and row["linear_solves"] == 9
            and row["wall_time_runs_s"] == [3.0, 1.0, 2.0])


def test_compare_against_direct_and_one_rank():
    rows = [{"example": 1, "mesh_size": 0.5, "method": m, "ranks": r, "value": v, "exact": 2.0,
             "wall_time_s": t}
            for m, r, v, t in (("direct", 1, 2.2, 8.0), ("newton", 1, 2.2022, 2.0),
                               ("newton", 2, 2.2022, 1.0))]
    compare(rows)
    assert abs(rows[1]["vs_direct"] - 1e-3) < 1e-12
    assert rows[1]["speedup_vs_direct"] == 4.0 and rows[2]["speedup_vs_1_rank"] == 2.0
    assert abs(rows[0]["error"] - 0.1) < 1e-12 and rows[2]["vs_direct"] is None


def test_compare_axisymmetric_against_plane_strain():
    rows = [{"example": 2, "mesh_size": 0.05, "method": "newton", "ranks": 1, "symmetry": s,
             "value": 1.0, "exact": None, "wall_time_s": t}
            for s, t in (("plane_strain", 2.0), ("axisymmetric", 2.5))]
    compare(rows)
    assert rows[1]["time_vs_plane_strain"] == 1.25 and rows[0]["time_vs_plane_strain"] is None


def test_free_surface_bench_pairs_each_scene_fixed_and_free():
    """`forming bench --free-surface` on Example 2 (mu = 0), launched in this process: the fixed
    run's 14 solves, the free run's three updates and 30 solves (29 while a warm start could end on
    its first iterate: FlowProblem.carry_from), the strip 1.5 % under the land;
    the table holds both rows with their ratios (the whole bench's wall-time ratios on one rank:
    docs/free_surface.md)."""
    def launch(case, ranks):
        return run_case(case)

    rows = free_surface_bench(1, 1, launch, ("Example 2, mu = 0",))
    fixed, free = rows
    assert fixed["linear_solves"] == 14 and free["updates"] == 3 and free["linear_solves"] == 30
    assert free["size_change"] == pytest.approx(-0.0146, abs=1e-3)
    assert free["solves_vs_fixed"] == pytest.approx(30 / 14) and free["time_vs_fixed"] > 1
    assert "| Example 2, mu = 0 | " in free_surface_table(rows)
