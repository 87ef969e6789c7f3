"""Boundary roles of a workpiece mesh, named as in section 2 of the paper.

Gamma1 process velocity (2.5), Gamma2/Gamma4 free (2.6), Gamma3 die contact (2.9), Gamma5 applied
force (2.7), Gamma6 symmetry (2.8) about y = 0 and, in 3D, Gamma7 about z = 0: the physical-group
names of a .msh file and the facet-tag values of a mesh.
"""
ROLES = {"gamma1_velocity": 1, "gamma2_free": 2, "gamma3_contact": 3,
         "gamma4_free": 4, "gamma5_force": 5, "gamma6_symmetry": 6, "gamma7_symmetry": 7}
REQUIRED_ROLES = ("gamma1_velocity", "gamma3_contact", "gamma6_symmetry")
WORKPIECE = 1  # the physical group of the workpiece's cells
