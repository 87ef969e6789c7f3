"""The flow problem in finite elements: fields and boundary conditions, measures, the forms of
(3.5)-(3.12) and Newton's, the secant state, projections, the contact multiplier, the
frozen-coefficient protocol, and the one owner of assemble-lift-solve.
"""
