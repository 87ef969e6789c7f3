"""An exception on one MPI rank ends every rank with that rank's message: no deadlock, no
results."""
import os
import subprocess
import sys

import pytest
from mpi4py import MPI

from test_run_outputs import DEMO

# Rank 1 alone fails while writing the restart file, after the solve, where rank 0 goes on to a
# collective gather: without the abort rank 0 would wait for ever.
CHILD = """
import sys
from mpi4py import MPI
import forming_fenicsx.app.run as run
from forming_fenicsx.app.cli import main
original = run.save_velocity
def failing(path, u):
    if MPI.COMM_WORLD.rank == 1:
        raise RuntimeError("injected failure on this rank")
    original(path, u)
run.save_velocity = failing
sys.exit(main(["run", sys.argv[1], "--out", sys.argv[2], "--quiet",
               "--set", "discretisation.mesh_size=1.0",
               "--set", "output.fields=false", "--set", "output.figures=false"]))
"""


@pytest.mark.no_parallel_content  # the child's own mpirun -n 2 (tests/conftest.py)
def test_one_rank_failure_ends_all_ranks(shared_tmp):
    out = shared_tmp / "aborted"
    outcome = None
    if MPI.COMM_WORLD.rank == 0:
        env = {k: v for k, v in os.environ.items()
               if not k.startswith(("OMPI_", "PMIX_", "PRTE_", "OPAL_"))}
        env.update(OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                   OMPI_MCA_rmaps_base_oversubscribe="1",
                   PRTE_MCA_rmaps_default_mapping_policy=":oversubscribe")
        child = subprocess.run(["mpirun", "-n", "2", sys.executable, "-c", CHILD, DEMO, str(out)],
                               env=env, capture_output=True, text=True, timeout=300)
        outcome = (child.returncode, child.stderr)
    returncode, stderr = MPI.COMM_WORLD.bcast(outcome, root=0)
    assert returncode != 0
    assert "error on rank 1 of 2: RuntimeError: injected failure on this rank" in stderr
    assert not out.exists()  # nothing a user could take for a finished run
