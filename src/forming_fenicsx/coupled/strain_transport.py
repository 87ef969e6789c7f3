"""The equivalent strain of steady flow: u . grad(eps) = rate in the workpiece, eps = eps_in where
the material flows in (reference section 3).

Pure advection: an unstabilised Galerkin scheme oscillates. Two stable schemes, W the measure
weight (2 pi y when axisymmetric), (u.n)^- = max(-u.n, 0), degree p (the velocity's):
- "supg": continuous Lagrange with streamline-upwind Petrov-Galerkin test functions,
    int (u . grad eps - rate) (w + tau u . grad w) W dx + int (u.n)^- (eps - eps_in) w W ds = 0,
  tau = h / (2 p |u|), h = sqrt|det J| of the cell map;
- "upwind": discontinuous Lagrange with upwind fluxes: the same Galerkin term cell by cell plus,
  on every interior facet, (u.n)^- [eps] w W from the side the flow leaves (the jump to the
  upwind value is penalised where the flow enters a cell).
Both impose the inflow condition weakly where the velocity enters (at more than 30 degrees to the
boundary: not on die walls and free surfaces, which it follows), on any boundary shape, and are
consistent (the exact eps satisfies them). A side the flow enters at less than 30 degrees gets no
condition, and the error there stalls (docs/strain_transport.md).

docs/strain_transport.md compares them on velocities with exact strain
(tests/test_strain_transport.py): both reach the order p + 1 when the strain rate is accurate and
agree with the velocity in Q_p, as the flow gives it (its strain rate is O(h^p): order 2 for Q1
and Q2 alike). At a step of the inflow strain SUPG over- and undershoots about half as much as
upwind DG (exact only when the step lies on a mesh line and the flow along the mesh lines), and
upwind DG, with 2 to 4 times the unknowns, takes 2 to 3 times as long. Hence SUPG, the default.
One linear solve (GMRES with ILU(1), SOLVER; option prefix ``strain_``) per velocity.
"""
from __future__ import annotations

from typing import Callable

import dolfinx.fem
import numpy as np
import ufl
from petsc4py import PETSc

from forming_fenicsx.config.strain_profile import profile_values
from forming_fenicsx.core.compat import function_space
from forming_fenicsx.coupled.cached_solve import CachedSolve
from forming_fenicsx.fem.linear_problem import DIRECT, LinearProblem
from forming_fenicsx.physics.coordinates import CoordinateSystem

PREFIX = "strain"
# GMRES with block-Jacobi ILU(1) in reverse Cuthill-McKee order (MUMPS LU should it fail): faster
# than MUMPS LU on the hardening scenes (ILU(0) does not converge there; docs/hardening.md). SUPG
# only: upwind DG's error stalls with it (MUMPS LU there)
SOLVER = {"ksp_type": "gmres", "ksp_rtol": 1e-10, "ksp_max_it": 200, "pc_type": "bjacobi",
          "sub_pc_type": "ilu", "sub_pc_factor_levels": 1, "sub_pc_factor_mat_ordering_type": "rcm"}
# Newton's coupling switches from the relaxed step to the strain in the tangent once the strain
# changes by less than TANGENT_FROM of its gain (3e-2: the fastest of 1e-2, 3e-2 and 1e-1 on
# annealed copper; switching at once stops short), or after TANGENT_AFTER relaxed freezes (a
# relaxed step that never settles: the plane-strain strip, an annealed strip rolled with back
# tension); docs/hardening.md
TANGENT_FROM = 3e-2
TANGENT_AFTER = 8


class StrainField:
    """The transported equivalent strain ``eps`` (a Lagrange Function of the velocity's degree) of a
    velocity field, and the frozen-coefficient protocol (frozen.py) that couples it to the flow:
    ``freeze(u)`` solves the transport with u; ``change(u)`` is ||eps(u) - eps|| / ||eps|| in the
    weighted L2 norm (one transport solve, kept for the next freeze at the same u)."""

    name = "strain"
    tangent = True  # Newton's step can carry its derivative (strain_tangent.py)

    coupled = True  # a field of its own, unlike the friction bound (FlowProblem.coupled_settled)

    def __init__(self, u: dolfinx.fem.Function, coordinates: CoordinateSystem, inflow_strain,
                 degree: int, quadrature_degree: int, scheme: str = "supg",
                 options: dict | None = None, relaxation: float = 0.5, tangent_from: float = 0.0,
                 eps: dolfinx.fem.Function | None = None):
        """``eps``: the Function to transport into (a flow law's strain coefficient), one of
        ``degree`` and the scheme's family; a new one unless given."""
        mesh = u.function_space.mesh
        self.space = function_space(mesh, "P" if scheme == "supg" else "DP", degree) \
            if eps is None else eps.function_space
        self.eps = eps if eps is not None else dolfinx.fem.Function(self.space,
                                                                    name="equivalent_strain")
        # the strain flowing in at points (N, 2) of the entry (post.streamlines): the inflow
        # strain when it is a number, else set by whoever knows the profile (coupled.coupling)
        self.entry_strain: Callable[[np.ndarray], np.ndarray] | None = None
        if isinstance(inflow_strain, (int, float)):
            value = float(inflow_strain)
            self.entry_strain = lambda points: np.full(len(points), value)
        self._candidate = dolfinx.fem.Function(self.space)
        self.velocity = dolfinx.fem.Function(u.function_space)  # the velocity eps belongs to
        self._coordinates = coordinates
        v = self.velocity
        eps, w = ufl.TrialFunction(self.space), ufl.TestFunction(self.space)
        metadata = {"quadrature_degree": quadrature_degree}
        dx = coordinates.measure(ufl.dx(domain=mesh, metadata=metadata))
        ds = coordinates.measure(ufl.ds(domain=mesh, metadata=metadata))
        normal = ufl.FacetNormal(mesh)
        # the inflow faces: where the velocity enters at more than 30 degrees to the boundary; a
        # die wall or free surface, that the flow follows, has no condition (a characteristic
        # boundary) even where the discrete u.n is slightly negative
        entering = -ufl.dot(v, normal)
        inflow = ufl.conditional(ufl.gt(entering, 0.5 * ufl.sqrt(ufl.dot(v, v))), entering, 0.0)
        rate = coordinates.equivalent_strain_rate(v)
        if scheme == "supg":
            # the cell size, the volume's dim-th root (CellDiameter: Q1 only)
            h = cell_size(mesh)
            speed = ufl.sqrt(ufl.dot(v, v)) + 1e-300
            test = w + h / (2 * degree * speed) * ufl.dot(v, ufl.grad(w))
            jumps = 0
        elif scheme == "upwind":
            test = w
            dS = coordinates.measure(ufl.dS(domain=mesh, metadata=metadata))
            entering = {side: ufl.max_value(-ufl.dot(v(side), normal(side)), 0.0)
                        for side in ("+", "-")}
            jumps = (entering["+"] * (eps("+") - eps("-")) * w("+")
                     + entering["-"] * (eps("-") - eps("+")) * w("-")) * dS
        else:
            raise ValueError(f"scheme must be supg or upwind; got {scheme!r}")
        bilinear = ufl.dot(v, ufl.grad(eps)) * test * dx + inflow * eps * w * ds + jumps
        linear = rate * test * dx + inflow * inflow_strain * w * ds
        self._system = LinearProblem(
            dolfinx.fem.form(bilinear), [dolfinx.fem.form(linear)], self._candidate, prefix=PREFIX,
            options={**DIRECT, **(SOLVER if scheme == "supg" else {}), **(options or {})},
            fallback=True)
        self._cached = CachedSolve(self._system, self.velocity, self.eps, "strain")
        # the transport residual R(eps(u), u) at the last solve, for its velocity derivative
        self._residual = ufl.replace(bilinear, {eps: self._candidate}) - linear
        self._dx = dx
        self._norm = dolfinx.fem.form(self._candidate ** 2 * dx)
        self._difference = dolfinx.fem.form((self._candidate - self.eps) ** 2 * dx)
        # the strain the iteration starts from (the inflow strain everywhere, kept at the first
        # freeze): the switch to the tangent measures the change against the strain gained
        self._start: dolfinx.fem.Function | None = None
        self._gained = None
        self._relaxation, self._tangent_from = relaxation, tangent_from
        # eps = eps(u) at every freeze, and its derivative in Newton's step (strain_tangent.py)
        self.in_tangent = False
        self._relaxed_freezes = 0

    def solve(self, u: dolfinx.fem.Function) -> dolfinx.fem.Function:
        """eps of the velocity u (into ``_candidate``; collective), kept for the next call at the
        same u (cached_solve.py); a velocity that is zero everywhere (before the first solve)
        carries no strain: eps stays as it is."""
        return self._cached.solve(u)

    def freeze(self, u: dolfinx.fem.Function) -> None:
        """eps <- eps + relaxation (eps(u) - eps); with ``tangent_from`` > 0 (Newton), once the
        change of the gain falls below it (or after TANGENT_AFTER freezes), eps <- eps(u) with
        ``in_tangent`` set: Newton's step then carries the strain's derivative
        (strain_tangent.py). Far from the answer the tangent's steps stop short of it on
        pre-strained stock; near it the relaxed step crawls along the slow mode of strain and
        velocity following each other (docs/hardening.md: the couplings measured)."""
        if not self.in_tangent and self._tangent_from > 0.0:
            # the change only while the switch can still happen (it also solves for u)
            self._relaxed_freezes += 1
            self.in_tangent = (0.0 < self._change_of_gain(u) < self._tangent_from
                               or self._relaxed_freezes > TANGENT_AFTER)
        candidate = self.solve(u).x.array
        relaxation = 1.0 if self.in_tangent else self._relaxation
        self.eps.x.array[:] += relaxation * (candidate - self.eps.x.array)
        self.eps.x.scatter_forward()

    @property
    def coefficient(self) -> dolfinx.fem.Function:
        """The Function the flow law reads (strain_tangent.py differentiates the flow by it)."""
        return self.eps

    def settle(self, u: dolfinx.fem.Function) -> None:
        """eps <- eps(u), the transport of u itself."""
        self.eps.x.array[:] = self.solve(u).x.array
        self.eps.x.scatter_forward()

    def start_at(self, u: dolfinx.fem.Function) -> None:
        """eps <- eps(u) (the strain is a function of the velocity alone), and for Newton the
        strain's derivative in the step from the first: the relaxed freezes that lead a cold start
        there took a free-surface update's warm start 12 steps (docs/free_surface.md)."""
        self._keep_start()  # the gain's reference: the inflow strain, before it is replaced
        self.settle(u)
        self.in_tangent = self._tangent_from > 0.0

    def snapshot(self) -> object:
        return self.eps.x.array.copy(), self.in_tangent, self._relaxed_freezes

    def restore(self, saved: object) -> None:
        self.eps.x.array[:], self.in_tangent, self._relaxed_freezes = saved
        self._cached.forget()

    def change(self, u: dolfinx.fem.Function) -> float:
        """||eps(u) - eps|| / ||eps(u)|| in the weighted L2 norm (collective)."""
        return self._relative(u, self._norm)

    def _change_of_gain(self, u: dolfinx.fem.Function) -> float:
        """||eps(u) - eps|| / ||eps(u) - eps_start||, eps_start the strain of the first freeze: on a
        pre-strained stock ||eps(u)|| is mostly the inflow strain, and a change relative to it
        would switch to the tangent while the velocity still moves by percents
        (docs/hardening.md)."""
        self._keep_start()
        return self._relative(u, self._gained)

    def _keep_start(self) -> None:
        """eps_start, the strain the iteration starts from, kept once (with the gain's norm)."""
        if self._start is None:
            self._start = self.eps.copy()
            self._gained = dolfinx.fem.form((self._candidate - self._start) ** 2 * self._dx)

    def _relative(self, u: dolfinx.fem.Function, reference: dolfinx.fem.Form) -> float:
        """||eps(u) - eps|| over the square root of ``reference`` (collective; 0 when it is 0)."""
        self.solve(u)
        comm = self.space.mesh.comm
        norm = comm.allreduce(dolfinx.fem.assemble_scalar(reference))
        difference = comm.allreduce(dolfinx.fem.assemble_scalar(self._difference))
        return float(np.sqrt(difference / norm)) if norm > 0 else 0.0

    def velocity_derivative(self, direction) -> ufl.Form:
        """dR/du [direction] of the transport residual R(eps, u) = a(u; eps, w) - L(u; w) at the
        last solve (eps = eps(u)): the bilinear form C of the strain's sensitivity
        d eps = -D^-1 C du, D the transport matrix."""
        return ufl.derivative(self._residual, self.velocity, direction)

    def transport_solve(self, b: PETSc.Vec, x: PETSc.Vec) -> None:
        """x = D^-1 b with the transport matrix of the last solve."""
        self._system.solve_system(x, b)

    def destroy(self) -> None:
        self._system.destroy()


def cell_size(mesh) -> ufl.core.expr.Expr:
    """A cell's size for SUPG: |det J|^(1/d) of its map (d = 2 or 3), sqrt(|det J|) in 2D."""
    volume = abs(ufl.JacobianDeterminant(mesh))
    return ufl.sqrt(volume) if mesh.geometry.dim == 2 else volume ** (1.0 / 3.0)


def inflow_strain(mesh, degree: int, profile: np.ndarray, half_size: float):
    """A strain profile across the entry (config.strain_profile) as a Lagrange Function of
    ``degree`` on the mesh, a function of y alone: the inflow strain of the transport and its
    first guess everywhere."""
    target = dolfinx.fem.Function(function_space(mesh, "P", degree), name="inflow_strain")
    y = target.function_space.tabulate_dof_coordinates()[:, 1]
    target.x.array[:] = profile_values(profile, np.abs(y), half_size)
    return target
