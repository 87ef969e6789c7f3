"""The workpiece mesh with named boundary roles (gmsh), point evaluation across ranks, and fields
carried from one mesh to another.
"""
