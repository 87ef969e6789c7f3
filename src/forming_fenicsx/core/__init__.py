"""The bottom layer: errors, units and relative values, boundary roles, the dolfinx/NumPy version
differences, PETSc option prefixes, CSV tables, Richardson extrapolation, number parsing,
Anderson mixing.
"""
