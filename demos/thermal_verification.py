# # The steady heat equation against exact solutions (docs/thermal.md)
#
#     mpirun -n 2 python demos/thermal_verification.py
#
# Prints the 1-D advection-diffusion layer at Peclet 1e1 to 1e5 (over- and undershoots, errors
# upstream of the layer), the manufactured solutions' errors and orders in both symmetries, and the
# adiabatic limit of the smooth cone and wedge flows with the heat balances.
from mpi4py import MPI

from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.verification.thermal_verification import adiabatic, layer, manufactured, orders

tables = []
for cells in (20, 5):
    rows = []
    for degree in (1, 2):
        for peclet in (1e1, 1e2, 1e3, 1e4, 1e5):
            r = layer(peclet, cells, degree)
            rows.append([f"Q{degree}", f"{peclet:.0e}", f"{r['cell_peclet']:.3g}",
                         *(f"{r[key]:.1e}" for key in ("overshoot", "undershoot",
                                                       "error_first_half", "error_outside_layer"))])
    tables.append(markdown_table(
        f"1-D layer u T' = k T'', T(0) = 0, T(1) = 1, {cells} cells, sampled at 20 points per cell",
        ["element", "Pe", "cell Pe", "overshoot", "undershoot", "error x <= 1/2",
         "error outside last cell"], rows))

rows = []
for symmetry in ("plane_strain", "axisymmetric"):
    for degree in (1, 2):
        runs = [manufactured(symmetry, degree, cells) for cells in (4, 8, 16, 32)]
        l2, h1 = orders([r["l2"] for r in runs]), orders([r["h1"] for r in runs])
        rows.append([symmetry, f"Q{degree}", f"{runs[-1]['l2']:.2e}", f"{runs[-1]['h1']:.2e}",
                     " / ".join(f"{o:.2f}" for o in l2), " / ".join(f"{o:.2f}" for o in h1),
                     " / ".join(f"{r['residual']:.1e}" for r in runs)])
tables.append(markdown_table(
    "Manufactured solutions, 4 to 32 cells a side: relative errors on 32, orders, balance "
    "residuals",
    ["symmetry", "element", "L2 error", "H1 error", "L2 orders", "H1 orders", "balance residual"],
    rows))

rows = []
for symmetry in ("axisymmetric", "plane_strain"):
    for degree in (1, 2):
        for cells in (4, 8, 16):
            r = adiabatic(symmetry, degree, cells)
            rows.append([symmetry, f"Q{degree}", cells, f"{r['exit_rise']:.6f}",
                         f"{r['exact_rise']:.6f}", f"{r['exit_rise'] / r['exact_rise'] - 1:.1e}",
                         f"{r['residual']:.1e}", f"{r['global_residual']:.1e}"])
    r = adiabatic(symmetry, 1, 4, softening=0.1)
    rows.append([symmetry, "Q1, softening 0.1", 4, f"{r['exit_rise']:.6f}",
                 f"{r['exact_rise']:.6f}", f"{r['exit_rise'] / r['exact_rise'] - 1:.1e}",
                 f"{r['residual']:.1e}", f"{r['freezes']} freezes"])
tables.append(markdown_table(
    "Adiabatic limit (kappa = 0, no tool contact): mixing-cup exit rise against beta W/(rho c)",
    ["symmetry", "element", "cells", "exit rise", "exact", "relative error", "heat balance",
     "global balance"], rows))
if MPI.COMM_WORLD.rank == 0:
    print("\n\n".join(tables))
