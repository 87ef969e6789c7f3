"""`forming run`: the files of a run, their keys and contents, and a run that does not converge."""
import csv
import json
import logging
import os
import signal
import subprocess
import sys
import xml.etree.ElementTree as ElementTree
from pathlib import Path

import pytest
from conftest import kept_figures
from mpi4py import MPI

from forming_fenicsx import load_scene
from forming_fenicsx.app.cli import main
from forming_fenicsx.app.run import solve_scene

DEMO = str(Path(__file__).parents[1] / "demos" / "example1_extrusion.toml")
COARSE = ["--set", "discretisation.mesh_size=1.0", "--quiet"]
# For the runs whose test reads neither fields.xdmf nor a figure (the figures took 0.95 s of each
# run on this mesh); test_run_writes_summary_history_fields_and_figures checks both
NO_FIELDS_NO_FIGURES = ["--set", "output.fields=false", "--set", "output.figures=false"]
REQUIRED = {"scene", "dolfinx_version", "mpi_ranks", "dofs", "converged", "linear_solves",
            "outer_iterations", "wall_time_s", "ram_pressure", "mean_hydrostatic_pressure",
            "die_force_x", "force_balance_residual"}


def test_run_writes_summary_history_fields_and_figures(shared_tmp):
    out = shared_tmp / "run"
    with kept_figures() as figures:
        assert main(["run", DEMO, "--out", str(out), "--set", "friction.mu=0.1", *COARSE,
                     "--", "-ksp_type", "preonly"]) == 0
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert REQUIRED <= set(summary)
    assert summary["converged"] is True and summary["mpi_ranks"] == MPI.COMM_WORLD.size
    assert (summary["scene"]["friction"]["mu"] == 0.1
            and summary["scene"]["discretisation"]["mesh_size"] == 1.0)
    assert summary["force_balance_residual"] < 1e-2
    with (out / "history.csv").open() as stream:
        rows = list(csv.DictReader(stream))
    assert len(rows) == summary["linear_solves"]
    assert float(rows[-1]["relative_increment"]) < 1e-4
    assert [int(r["outer"]) for r in rows][-1] == summary["outer_iterations"] - 1
    names = {a.get("Name") for a in ElementTree.parse(out / "fields.xdmf").iter("Attribute")}
    assert names == {"velocity", "equivalent_strain_rate", "hydrostatic_pressure",
                     "secant_viscosity"}
    assert (out / "fields.h5").stat().st_size > 1000
    for figure in ("velocity.png", "strain_rate.png", "die.png"):
        assert (out / figure).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    if MPI.COMM_WORLD.rank == 0:  # a converged run's figures carry no failure
        assert sorted(figures) == ["die.png", "strain_rate.png", "velocity.png"]
        assert not any("NOT CONVERGED" in f.axes[0].get_title() for f in figures.values())


def test_not_converged_exits_non_zero_and_keeps_last_iterate(shared_tmp, capsys):
    out = shared_tmp / "short"
    with kept_figures() as figures:
        assert main(["run", DEMO, "--out", str(out), "--set", "solver.max_iterations=3",
                     *COARSE]) == 3
    MPI.COMM_WORLD.barrier()
    if MPI.COMM_WORLD.rank == 0:
        assert "not converged" in capsys.readouterr().err
        # every figure says so first in its title, with the reason's first clause
        assert sorted(figures) == ["die.png", "strain_rate.png", "velocity.png"]
        for figure in figures.values():
            assert figure.axes[0].get_title().startswith(
                "NOT CONVERGED: no convergence in 3 iterations\n")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and "3 iterations" in summary["reason"]
    assert summary["linear_solves"] == 4
    assert (out / "fields.xdmf").exists()


def test_existing_output_is_kept_without_force_and_replaced_with_it(shared_tmp, capsys):
    out = shared_tmp / "existing"
    if MPI.COMM_WORLD.rank == 0:
        out.mkdir()
        (out / "mine.txt").write_text("keep me")
    MPI.COMM_WORLD.barrier()
    assert main(["run", DEMO, "--out", str(out), *COARSE]) == 2
    assert (out / "mine.txt").read_text() == "keep me"
    if MPI.COMM_WORLD.rank == 0:
        assert "--force" in capsys.readouterr().err
    assert main(["run", DEMO, "--out", str(out), *COARSE, "--force", *NO_FIELDS_NO_FIGURES]) == 0
    MPI.COMM_WORLD.barrier()
    assert not (out / "mine.txt").exists() and (out / "summary.json").exists()
    assert not [p for p in shared_tmp.iterdir() if ".partial-" in p.name]  # no staging folder left


def test_failed_linear_solve_stops_with_reason_and_keeps_last_iterate(shared_tmp):
    out = shared_tmp / "ksp"
    # an unpreconditioned CG limited to 2 iterations cannot solve the first system
    assert main(["run", DEMO, "--out", str(out), *COARSE, "--", "-ksp_type", "cg",
                 "-pc_type", "none", "-ksp_max_it", "2"]) == 3
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert ("linear solve failed at outer 0, inner 0" in summary["reason"]
            and "penalty" in summary["reason"])


class _SignalAtThirdIterate(logging.Handler):
    """Sends SIGTERM to this process when rank 0 logs the third inner iterate (as a user would)."""

    def emit(self, record):
        if "inner   3" in record.getMessage():
            os.kill(os.getpid(), signal.SIGTERM)


def test_sigterm_ends_the_run_cleanly_with_the_last_iterate(shared_tmp):
    out = shared_tmp / "sigterm"
    logger = logging.getLogger("forming_fenicsx")
    handler = _SignalAtThirdIterate()
    logger.addHandler(handler)
    try:
        code = main(["run", DEMO, "--out", str(out), "--set", "discretisation.mesh_size=1.0",
                     "--set", "output.fields=false", "--set", "output.figures=false"])
    finally:
        logger.removeHandler(handler)
    MPI.COMM_WORLD.barrier()
    assert code == 3
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False
    assert summary["reason"].startswith("interrupted by SIGTERM at outer 0, inner 3")
    # the uniform start and three secant iterates, all on every rank
    assert summary["linear_solves"] == 4
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # the handler is restored


def test_restart_from_a_previous_run(shared_tmp, capsys):
    first, second = shared_tmp / "first", shared_tmp / "second"
    assert main(["run", DEMO, "--out", str(first), *COARSE, *NO_FIELDS_NO_FIGURES]) == 0
    assert main(["run", DEMO, "--out", str(second), *COARSE, *NO_FIELDS_NO_FIGURES,
                 "--restart", str(first)]) == 0
    MPI.COMM_WORLD.barrier()
    a = json.loads((first / "summary.json").read_text())
    b = json.loads((second / "summary.json").read_text())
    assert b["restarted_from"] == str(first)
    assert b["linear_solves"] <= 2 < a["linear_solves"]
    assert b["ram_pressure"] == pytest.approx(a["ram_pressure"], rel=1e-4)
    # the restart file does not depend on the partition: restart this rank's own serial solve from
    # it
    scene = load_scene(DEMO, ["discretisation.mesh_size=1.0"])
    serial = solve_scene(scene, comm=MPI.COMM_SELF, restart=first)[2]
    assert (serial["linear_solves"] <= 2
            and serial["ram_pressure"] == pytest.approx(a["ram_pressure"], rel=1e-4))
    # another mesh is refused before solving
    assert main(["run", DEMO, "--out", str(shared_tmp / "other"), "--quiet",
                 "--restart", str(first), "--set", "discretisation.mesh_size=0.5"]) == 2
    if MPI.COMM_WORLD.rank == 0:
        assert "not the same mesh" in capsys.readouterr().err


def test_zero_pivot_stops_with_reason(shared_tmp):
    """PETSc's own LU told that every pivot is zero (on 2 ranks it refuses the parallel matrix):
    either way the run ends at the first solve with the reason, not a traceback."""
    out = shared_tmp / "pivot"
    assert main(["run", DEMO, "--out", str(out), *COARSE, "--", "-pc_type", "lu",
                 "-pc_factor_mat_solver_type", "petsc", "-pc_factor_zeropivot", "1e300"]) == 3
    MPI.COMM_WORLD.barrier()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["converged"] is False and summary["linear_solves"] == 0
    assert "linear solve failed at outer 0, inner 0" in summary["reason"]


@pytest.mark.no_parallel_content  # a serial child process (tests/conftest.py)
def test_quiet_run_with_a_cold_form_cache_prints_nothing_and_the_folder_has_user_permissions(
        shared_tmp):
    """A first run compiles every form (FFCx logs each gcc command through the root logger's
    handler, about 30 lines before the fix): with --quiet a converged run without warnings prints
    nothing, and the output folder gets the user's umask (it was mkdtemp's 0700). Run in a child
    process (rank 0) with an empty form cache."""
    out = shared_tmp / "quiet"
    if MPI.COMM_WORLD.rank == 0:
        env = {k: v for k, v in os.environ.items()
               if not k.startswith(("OMPI_", "PMIX_", "PRTE_", "OPAL_"))}
        env.update(XDG_CACHE_HOME=str(shared_tmp / "cold-cache"), OMPI_ALLOW_RUN_AS_ROOT="1",
                   OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
        done = subprocess.run([sys.executable, "-m", "forming_fenicsx.app.cli", "run", DEMO,
                               "--out", str(out), *COARSE, "--set", "output.fields=false",
                               # the paper's d = 1e-3 loses 2.9 % of the volume here, and warns
                               "--set", "output.figures=false", "--set", "penalty.d=1e-4"],
                              capture_output=True, text=True, env=env, timeout=600)
        assert done.returncode == 0, done.stderr[-2000:]
        # the forms were compiled, not taken from a cache
        assert (shared_tmp / "cold-cache").is_dir()
        assert done.stdout == "" and done.stderr == ""
        umask = os.umask(0)
        os.umask(umask)
        assert out.stat().st_mode & 0o777 == 0o777 & ~umask
    MPI.COMM_WORLD.barrier()
    assert json.loads((out / "summary.json").read_text())["warnings"] == []


def test_the_command_drops_ffcx_advice_on_integration_points():
    """A new user's square bar in inches on 2 ranks, --quiet, printed FFCx's UserWarning on a 3D
    form's 121 integration points (through py.warnings and the root logger's handler) on its first
    compile: the command's filter drops it, as it drops the compiler's build lines, and lets any
    other warning through."""
    from forming_fenicsx.app.cli import _not_a_compiler_line

    def record(name: str, message: str) -> logging.LogRecord:
        return logging.LogRecord(name, logging.WARNING, "/usr/lib/python3/warnings.py", 1, message,
                                 None, None)

    advice = ("/usr/lib/python3/dist-packages/ffcx/element_interface.py:81: UserWarning: Number "
              "of integration points per cell is: 121. Consider using 'quadrature_degree' to "
              "reduce number.")
    assert not _not_a_compiler_line(record("py.warnings", advice))
    assert _not_a_compiler_line(record("py.warnings", "UserWarning: something else"))
    assert _not_a_compiler_line(record("forming_fenicsx", "Number of integration points"))


def test_a_run_leaves_no_petsc_options_behind():
    """PETSc's options database holds 512 entries: each run's prefixed solver options are removed
    when its solvers are destroyed (the whole suite in one process once filled it)."""
    from petsc4py import PETSc

    before = set(PETSc.Options().getAll())
    solve_scene(load_scene(DEMO, ["discretisation.mesh_size=1.0", "solver.method=newton",
                                  "discretisation.averaging=quadrature", "output.fields=false"]))
    assert set(PETSc.Options().getAll()) == before


def test_summary_json_takes_numpy_scalars(tmp_path):
    """A free surface that settled on a numpy comparison (np.bool_) crashed the new user's CSV-die
    drawing run after it had converged ("Object of type bool_ is not JSON serializable"): numpy
    scalars are written as Python's, non-finite floats as null."""
    import numpy as np

    from forming_fenicsx.io.output import write_summary

    path = tmp_path / "summary.json"
    write_summary(path, {"free_surface": {"converged": np.bool_(True), "move": np.float64(2.5),
                                          "history": [{"updates": np.int64(3)}]},
                         "ratio": np.float64(np.nan), "plain": 1.5})
    assert json.loads(path.read_text()) == {
        "free_surface": {"converged": True, "move": 2.5, "history": [{"updates": 3}]},
        "ratio": None, "plain": 1.5}
