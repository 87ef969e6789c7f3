"""Files of a run but its figures: summary.json, history.csv, die.csv, the exit profiles' CSV,
fields.xdmf (with its .h5) and velocity.npz (the restart)."""
from __future__ import annotations

import csv
import json
import math
import xml.etree.ElementTree as ElementTree
from pathlib import Path
from typing import Any

import numpy as np
from dolfinx.io import XDMFFile

from forming_fenicsx.solvers.records import IterationRecord
from forming_fenicsx.core.units import Units


def json_safe(value: Any) -> Any:
    """``value`` with every numpy scalar made a Python one and every non-finite float (nested in
    dicts and lists) replaced by None: valid JSON."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def write_summary(path: Path, summary: dict[str, Any]) -> None:
    """summary.json; non-finite numbers are written as null."""
    path.write_text(json.dumps(json_safe(summary), indent=2) + "\n")


def write_history(path: Path, history: list[IterationRecord]) -> None:
    """history.csv: a row per linear solve (residual norm, step length and switch counts for Newton
    steps, else nan, 1 and -1; an iterative solve's outer and velocity-block Krylov iterations,
    else 1 and 0)."""
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow(["outer", "inner", "relative_increment", "elapsed_s",
                         "solve_error_estimate", "residual_norm", "step_length", "law_switches",
                         "contact_switches", "krylov_iterations", "velocity_iterations"])
        for record in history:
            writer.writerow([record.outer, record.inner, f"{record.increment:.6e}",
                             f"{record.elapsed:.4f}", f"{record.solve_error:.3e}",
                             f"{record.residual:.6e}", f"{record.step:.6g}",
                             record.law_switches, record.contact_switches,
                             record.krylov_iterations, record.velocity_iterations])


def write_fields(path: Path, mesh, fields) -> None:
    """fields.xdmf: one mesh carrying every field under its fixed name (collective).

    dolfinx writes the .h5 datasets and an .xdmf with the mesh grid and a grid per function over
    the same mesh (ParaView then draws the other grids, in solid grey, over the one coloured by a
    field); rank 0 then rewrites the XML as one grid (single_grid_xdmf)."""
    with XDMFFile(mesh.comm, str(path), "w") as xdmf:
        xdmf.write_mesh(mesh)
        for field in fields:
            xdmf.write_function(field)
    mesh.comm.barrier()
    if mesh.comm.rank == 0:
        single_grid_xdmf(path)
    mesh.comm.barrier()


def single_grid_xdmf(path: Path, name: str = "workpiece") -> None:
    """Rewrite an .xdmf that dolfinx wrote (a mesh grid and a grid per function, dolfinx 0.5 to 0.9)
    as one uniform Grid holding the mesh grid's Topology and Geometry and every function's
    Attribute, each still pointing into the same .h5 datasets."""
    tree = ElementTree.parse(path)
    domain = tree.getroot().find("Domain")
    grids = domain.findall("Grid")
    mesh_grid = next(g for g in grids
                     if g.find("Topology") is not None and g.find("Geometry") is not None)
    grid = ElementTree.Element("Grid", Name=name, GridType="Uniform")
    grid.extend([mesh_grid.find("Topology"), mesh_grid.find("Geometry"),
                 *(a for g in grids if g is not mesh_grid for a in g.iter("Attribute"))])
    for old in grids:
        domain.remove(old)
    domain.append(grid)
    ElementTree.indent(tree, "  ")
    body = ElementTree.tostring(tree.getroot(), encoding="unicode")
    path.write_text(f'<?xml version="1.0"?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n{body}\n')


def write_die_profile(path: Path, profile: dict, units: Units) -> None:
    """die.csv: a row per node of Gamma3, ordered along the die (s from where the workpiece meets
    it; in 3D x, y, z ordered by x and around the section, post/die.py: die_profile); headers
    ``name [unit]`` when the scene names its units."""
    names = list(profile)
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([units.column(name) for name in names])
        for row in zip(*(profile[name] for name in names), strict=True):
            writer.writerow([f"{value:.8g}" for value in row])


def write_free_surface(path: Path, lines: dict[str, np.ndarray], units: Units) -> None:
    """free_surface.csv: the free surfaces' points (x, y and which surface: "product" after the
    die), each from upstream to downstream."""
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([units.column("x"), units.column("y"), "surface"])
        for name, points in lines.items():
            for x, y in points:
                writer.writerow([f"{x:.10g}", f"{y:.10g}", name])


def write_exit_profile(path: Path, profile: dict, name: str, units: Units) -> None:
    """exit_<quantity>.csv: y across the product (and z over a 3D product's exit section) and the
    quantity ``name`` (the ``values`` of exit_profiles.exit_profile or exit_strain_profile, or
    views3d.exit_section_values), the headers with their units (a 2D strain profile is the next
    pass's material.initial_strain_file: strain_profile.py reads it; a temperature in kelvin, and
    in units.temperature beside it when that is another unit)."""
    columns = [(units.column(axis), profile[axis]) for axis in ("y", "z") if axis in profile]
    columns += units.columns(name, profile["values"])
    with path.open("w", newline="") as stream:
        writer = csv.writer(stream)
        writer.writerow([header for header, _ in columns])
        for row in zip(*(values for _, values in columns), strict=True):
            writer.writerow([f"{value:.8g}" for value in row])


def save_velocity(path: Path, u) -> None:
    """velocity.npz: node coordinates and velocity of every node, gathered on rank 0 (collective).

    Independent of the partition, so a run on any number of ranks can restart from it.
    """
    space = u.function_space
    owned = space.dofmap.index_map.size_local
    dim = space.mesh.geometry.dim
    points = space.tabulate_dof_coordinates()[:owned, :dim]
    values = u.x.array.reshape(-1, dim)[:owned]
    parts = space.mesh.comm.gather((points, values), root=0)
    if space.mesh.comm.rank == 0:
        np.savez(path, points=np.concatenate([p for p, _ in parts]),
                 velocity=np.concatenate([v for _, v in parts]))


def load_velocity(path: Path, u) -> None:
    """Set u from a velocity.npz of the same mesh, matching nodes by their coordinates (collective).

    Raises ValueError when the saved mesh differs (another number of nodes or unmatched nodes).
    """
    space = u.function_space
    comm = space.mesh.comm
    with np.load(path) as saved:
        points, velocity = saved["points"], saved["velocity"]
    local = space.tabulate_dof_coordinates()[:, :space.mesh.geometry.dim]
    total = comm.allreduce(space.dofmap.index_map.size_local)
    if len(points) != total:
        raise ValueError(f"the restart velocity has {len(points)} nodes, this mesh {total}: "
                         "not the same mesh")
    scale = max(np.ptp(points, axis=0).max(), 1e-300)
    keys = {tuple(k): i for i, k in enumerate(np.round(points / scale * 1e9).astype(np.int64))}
    index = np.array([keys.get(tuple(k), -1)
                      for k in np.round(local / scale * 1e9).astype(np.int64)])
    if comm.allreduce(int((index < 0).sum())):
        raise ValueError("the restart velocity's nodes do not match this mesh: not the same mesh")
    u.x.array[:] = velocity[index].reshape(-1)
    u.x.scatter_forward()
