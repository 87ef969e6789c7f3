"""The constitutive and kinematic pieces, free of meshes and scenes: flow-stress laws (4.5) and
hardening, plane-strain or axisymmetric kinematics, the contact (3.4) and friction (3.11) terms,
closed-form solutions.
"""
