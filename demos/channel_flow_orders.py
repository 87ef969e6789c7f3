# # Power-law channel flow: observed convergence orders (verification.md)
#
#     mpirun -n 2 python demos/channel_flow_orders.py
#
# Prints the L2 and H1 velocity errors on 4, 8, 16 cells across the half channel and the observed
# orders, for Q1 and Q2 with the secant averaged at the nodes (the paper), at element centres, or
# evaluated at the quadrature points.
from mpi4py import MPI

from forming_fenicsx.core.report import markdown_table
from forming_fenicsx.verification.verification import channel_orders

rows = []
for n in (0.3, 0.5, 1.0):
    for element in ("Q1", "Q2"):
        for averaging in ("nodes", "centres", "quadrature"):
            errors, orders = channel_orders(n, element, averaging)
            rows.append([n, element, averaging, float(errors[-1, 0]), float(errors[-1, 1]),
                         " / ".join(f"{o:.2f}" for o in orders[:, 0]),
                         " / ".join(f"{o:.2f}" for o in orders[:, 1])])
if MPI.COMM_WORLD.rank == 0:
    print(markdown_table(
        "Power-law channel flow, errors on the finest mesh (16 cells) and observed orders",
        ["n", "element", "secant", "L2 error", "H1 error", "L2 orders", "H1 orders"], rows))
