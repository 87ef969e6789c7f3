# # Temperature of the aluminium rod extrusion (demos/aluminium_rod.toml), the flow isothermal
#
#     python demos/thermal_aluminium_rod.py [output.png [conductivity]]
#
# demos/aluminium_rod.toml with a [thermal] section (scene.Thermal), its flow solved, then the
# steady temperature of that flow (the problem's temperature field), one way: the rate power law
# does not read T. AA6063: rho c = 2800 kg/m^3 x 1064 J/(kg K) = 2.98 MPa/K, kappa = 201 W/(m K)
# = 201 N/(s K), beta = 0.9; billet in at 450 C; die at 450 C with h = 20 kW/(m^2 K)
# = 20 N/(mm s K); container at 420 C with h = 5; air at 20 C on the rod, h = 10 W/(m^2 K) = 0.01;
# friction heat c_T |u_T|^2 of the flow's friction, Blok's share against H13 steel (0.724).
# A conductivity other than 201 raises the Peclet number: 0.201 puts the container's at 1.9e3 and
# the rod's at 4.6e3, in the range of industrial extrusion.
# Prints the heat balance, the mixing-cup exit temperature beside the adiabatic estimate
# beta p_ram/(rho c) and the range of T, and draws T.
import sys
from pathlib import Path

import dolfinx.fem
import numpy as np
import ufl
from mpi4py import MPI

from forming_fenicsx.core.compat import function_space
from forming_fenicsx.app.run import solve_scene
from forming_fenicsx.config.loader import read_scene_data, scene_from_dict
from forming_fenicsx.coupled.thermal import ThermalMaterial, effusivity_share

KELVIN = 273.15
conductivity = float(sys.argv[2]) if len(sys.argv) > 2 else 201.0
share = effusivity_share(ThermalMaterial(2.98, conductivity), ThermalMaterial(3.59, 24.3))
data = read_scene_data(Path(__file__).parent / "aluminium_rod.toml")
data["thermal"] = {"heat_capacity": 2.98, "conductivity": conductivity, "heat_fraction": 0.9,
                   "inflow_temperature": 450 + KELVIN, "die_h": 20.0, "container_h": 5.0,
                   "container_temperature": 420 + KELVIN, "air_h": 0.01,
                   "air_temperature": 20 + KELVIN, "friction_share": share}
scene = scene_from_dict(data)
problem, result, summary = solve_scene(scene)
field = problem.field("temperature")  # T of the final flow, one way (solve_scene settled it)
ram_power = summary["ram_force"] * scene.process.velocity
balance = field.energy_balance(ram_power)
leaving = ufl.dot(field.velocity, field.n)
outflow = ufl.conditional(ufl.gt(leaving, 0), leaving, 0)
mixing_cup = field.integral(field.T * outflow, field.ds) / field.integral(outflow, field.ds)
mesh, T = problem.mesh, field.T.x.array
hottest = mesh.comm.allreduce(float(T.max()), op=MPI.MAX) - KELVIN
coldest = mesh.comm.allreduce(float(T.min()), op=MPI.MIN) - KELVIN
# for the figure: T at the cell vertices (Q1), each quadrilateral drawn as two triangles
vertex_space = function_space(mesh, "P", 1)
at_vertices = dolfinx.fem.Function(vertex_space)
at_vertices.interpolate(field.T)
cells = mesh.topology.index_map(2).size_local
quads = np.array([vertex_space.dofmap.cell_dofs(c) for c in range(cells)])
pieces = mesh.comm.gather((vertex_space.tabulate_dof_coordinates()[:, :2],
                           at_vertices.x.array - KELVIN,
                           np.vstack([quads[:, [0, 1, 3]], quads[:, [0, 3, 2]]])), root=0)
if mesh.comm.rank == 0:
    print(f"ram pressure {summary['ram_pressure']:.2f} MPa, ram power {ram_power:.1f} mW (N mm/s), "
          f"temperature solves {field.solves}")
    for key, value in balance.items():
        print(f"  {key}: {value:.5g}")
    print(f"friction share into the workpiece {share:.3f}")
    print(f"mixing-cup exit temperature {mixing_cup - KELVIN:.2f} C; adiabatic estimate "
          f"450 + beta p_ram/(rho c) = {450 + 0.9 * summary['ram_pressure'] / 2.98:.2f} C; "
          f"T from {coldest:.2f} to {hottest:.2f} C")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    offsets = np.cumsum([0] + [len(xy) for xy, _, _ in pieces])
    xy = np.concatenate([piece[0] for piece in pieces])
    values = np.concatenate([piece[1] for piece in pieces])
    triangles = np.concatenate([piece[2] + offset for piece, offset in zip(pieces, offsets)])
    fig, ax = plt.subplots(figsize=(10, 4))
    contour = ax.tricontourf(xy[:, 0], xy[:, 1], triangles, values, levels=30, cmap="inferno")
    fig.colorbar(contour, ax=ax, label="temperature [C]")
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm] (axis)")
    ax.set_ylabel("r [mm]")
    ax.set_title("AA6063 rod 50 -> 20 mm, ram 5 mm/s: steady temperature (flow isothermal)\n"
                 f"kappa = {conductivity:g} N/(s K)")
    out = sys.argv[1] if len(sys.argv) > 1 else "thermal_aluminium_rod.png"
    fig.savefig(out, dpi=120, bbox_inches="tight")
    print(f"wrote {out}")
field.destroy()
