# # Which non-smooth part of the operator is still changing while Newton converges
#
#     python demos/newton_kinks.py [--mesh-size 0.05] [--scene demos/example1_extrusion.toml]
#
# Newton's steps converge fast only once the points on each side of every kink of the operator have
# settled. After each linear solve this prints the relative increment and, against the previous
# iterate: the area of Gauss points whose rate crossed rate1 (the kink of (4.5) between the linear
# branch of the rigid zones and the power law, where the tangent stiffness drops by the factor
# alpha), the area that crossed rate2, and the length of die face whose contact state (u_N > 0,
# (3.4)) changed. docs/solvers.md shows a run on Example 1 at 242k unknowns. Every Newton run's
# history.csv counts the same switches (Gauss points across the kinks of the law, die nodes in and
# out of contact) per step; this script weighs them as areas and lengths, and separates rate1 from
# rate2.

import argparse
from pathlib import Path

import ufl
from mpi4py import MPI

import dolfinx.fem

from forming_fenicsx import load_scene
from forming_fenicsx.physics import contact
from forming_fenicsx.coupled.coupling import coupled_problem
from forming_fenicsx.mesh.geometry import build_mesh
from forming_fenicsx.solvers.newton import NewtonSolver
from forming_fenicsx.core.report import markdown_table

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--scene", default=str(Path(__file__).parent / "example1_extrusion.toml"))
parser.add_argument("--mesh-size", type=float, default=0.05)
args = parser.parse_args()

comm = MPI.COMM_WORLD
scene = load_scene(args.scene, ["solver.method=newton", "discretisation.averaging=quadrature",
                                f"discretisation.mesh_size={args.mesh_size}"])
problem = coupled_problem(scene, build_mesh(scene, comm))
u, last = problem.u, problem.u.copy()


def below(w, rate):
    return ufl.conditional(ufl.lt(problem.equivalent_strain_rate(w), rate), 1.0, 0.0)


def active(w):
    return ufl.conditional(ufl.gt(contact.normal_velocity(w, problem.n), 0.0), 1.0, 0.0)


# ## The measures, compiled once
rate1, rate2 = scene.material.rate1, scene.material.rate2
measures = {"area below rate1": below(u, rate1) * problem.dx,
            "area across rate1": (below(u, rate1) - below(last, rate1)) ** 2 * problem.dx,
            "area across rate2": (below(u, rate2) - below(last, rate2)) ** 2 * problem.dx}
if problem.has_contact:
    measures["contact length changed"] = (active(u) - active(last)) ** 2 * problem.ds_contact
forms = {name: dolfinx.fem.form(form) for name, form in measures.items()}
rows = []


def after_solve() -> str | None:
    """The solver's stop hook, called on every rank after every linear solve but the first (the
    uniform-modulus start): measure against the previous iterate; never stop."""
    rows.append([comm.allreduce(dolfinx.fem.assemble_scalar(form)) for form in forms.values()])
    last.x.array[:] = u.x.array
    return None


solver = NewtonSolver(problem, stop=after_solve)
result = solver.solve()
# solve 0 is the start and solve 1 is measured against the zero field: the table starts at solve 2
rows = [[index, f"{record.increment:.2e}", f"{record.step:.3g}", *row]
        for index, (row, record) in enumerate(zip(rows, result.history[1:], strict=True),
                                              start=1)][1:]
if comm.rank == 0:
    print(markdown_table(f"{Path(args.scene).stem}, h = {args.mesh_size}: "
                         f"{result.linear_solves} solves, "
                         f"{'converged' if result.converged else result.reason}",
                         ["solve", "increment", "step", *forms], rows))
