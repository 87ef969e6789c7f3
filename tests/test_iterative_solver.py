"""The iterative solver of the mixed formulation (fem/saddle_point.py: the augmented saddle point,
fieldsplit Schur with algebraic multigrid, FGMRES) against MUMPS (issue 36 (d))."""
from __future__ import annotations

import pytest
from mpi4py import MPI

from forming_fenicsx.app.bench_scale import growth_exponents, run_scale_case, scale_table
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import scene_from_dict
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.solvers.linear import ITERATIVE_FROM

BAR = {"process": {"kind": "drawing", "velocity": 1.0},
       "geometry": {"symmetry": "3d", "entry_height": 4.0, "exit_height": 3.2,
                    "entry_width": 6.0, "exit_width": 5.0, "die_angle": 8.0},
       "material": {"law": "piecewise_power", "A": 300.0}, "friction": {"mu": 0.05},
       "discretisation": {"averaging": "quadrature", "mesh_size": 1.0, "formulation": "mixed"},
       "solver": {"method": "newton"}, "output": {"fields": False, "figures": False}}


def _solved(linear: str, **sections: dict) -> tuple[dict, list[int]]:
    data = {key: dict(value) for key, value in BAR.items()}
    data.update(sections)
    data["solver"]["linear"] = linear
    _, result, summary = solve_scene(scene_from_dict(data))
    return summary, [record.krylov_iterations for record in result.history]


def test_iterative_agrees_with_direct():
    """A 4 x 6 -> 3.2 x 5 mm bar, 8 degrees, mu = 0.05, law (4.5), Newton on a 1 mm mesh (3147
    unknowns): the iterative solves take the run through the same Newton steps to the same answer,
    the drawing stress, die pressure and forces within 1e-6 of MUMPS' (measured: 5e-9), with the
    Krylov iterations counted per step."""
    direct, direct_krylov = _solved("direct")
    iterative, krylov = _solved("iterative")
    assert iterative["converged"] and direct["converged"]
    assert iterative["linear_solves"] == direct["linear_solves"]
    for key in ("drawing_stress", "mean_die_pressure", "drawing_force", "die_separation_force"):
        assert iterative[key] == pytest.approx(direct[key], rel=1e-6), key
    assert iterative["force_balance_residual"] < 1e-6
    assert set(direct_krylov) == {1} and min(krylov) > 1 and max(krylov) < 1000


def test_a_rate_independent_bar_gets_mumps_answer_by_the_direct_method():
    """The bar in annealed steel (Hollomon K = 530 MPa, n = 0.26: a viscosity contrast of 1e6).
    The direct method (3.13): each Krylov solve is stopped relative to the current iterate's
    residual, so its error shrinks with the increment and the fixed point is MUMPS' (measured
    8e-7; stopped relative to the right-hand side at 1e-10, it moved the answer by 4.7e-4).
    Newton: the Krylov solver does not converge on the tangent (no stiffness along the flow
    direction), and the run says so and goes on by the direct method from the secant start (1.5e-5
    from MUMPS' answer on 1 rank, 2.3e-4 on 2: within the direct method's own iteration error at
    solver.tolerance 1e-4, 3.4e-4 on the 0.8 mm mesh against tolerance 1e-6)."""
    hollomon = {"law": "hollomon", "K": 530.0, "n": 0.26}
    direct, _ = _solved("direct", material=hollomon, solver={"method": "direct"})
    iterative, _ = _solved("iterative", material=hollomon, solver={"method": "direct"})
    assert iterative["converged"] and direct["converged"]
    for key in ("drawing_stress", "mean_die_pressure"):
        assert iterative[key] == pytest.approx(direct[key], rel=1e-5), key
    newton, _ = _solved("iterative", material=hollomon, solver={"method": "newton"})
    assert newton["converged"] and "direct method (3.13) after Newton's linear solve" in \
        newton["reason"] and "rate-independent" in newton["reason"]
    assert newton["drawing_stress"] == pytest.approx(direct["drawing_stress"], rel=1e-3)


def test_iterative_needs_the_mixed_formulation():
    data = {key: dict(value) for key, value in BAR.items()}
    data["discretisation"]["formulation"] = "penalty"
    data["solver"]["linear"] = "iterative"
    with pytest.raises(SceneError, match="mixed"):
        scene_from_dict(data)


def test_auto_is_direct_below_the_threshold():
    """solver.linear = "auto" (the default) solves this small 3D mixed problem by MUMPS."""
    summary, krylov = _solved("auto")
    assert summary["converged"] and set(krylov) == {1}
    assert summary["dofs"] < ITERATIVE_FROM


def test_scale_case_row_and_growth_exponents():
    """`forming bench --scale`'s case (the bar at 1.2 mm, iterative) in this process: its Newton
    steps' Krylov iterations, and the exponent fit on rows whose time grows as N^1.5 and memory as
    N^1 exactly."""
    row = run_scale_case({"scale": True, "mesh_size": 1.2, "linear": "iterative"})
    assert row["converged"] and row["ranks"] == MPI.COMM_WORLD.size
    assert len(row["krylov_per_newton_step"]) >= 3
    assert 1 < max(row["krylov_per_newton_step"]) <= 200
    assert min(row["velocity_per_newton_step"]) > max(row["krylov_per_newton_step"]) - 1
    rows = [{"linear": "direct", "ranks": 1, "dofs": n, "wall_time_s": 2.0 * n**1.5,
             "solve_time_s": n**1.5, "peak_memory_mb": 3.0 * n} for n in (1e3, 8e3, 6.4e4)]
    (fit,) = growth_exponents(rows)
    assert fit["wall_time_s_exponent"] == pytest.approx(1.5, abs=1e-12)
    assert fit["peak_memory_mb_exponent"] == pytest.approx(1.0, abs=1e-12)
    shown = [{**r, "mesh_size": 1.0, "converged": True, "linear_solves": 9, "drawing_stress": 1.0,
              "krylov_per_newton_step": [], "velocity_per_newton_step": [], "vs_direct": None}
             for r in rows]
    assert "| 1.50 | 1.50 | 1.00 |" in scale_table(shown)
