"""The iterations: the secant methods (3.13) and (3.33), Newton's method with its line search and
fallback, the flow's linear solver, the records and messages of a run, accuracy on demand.
"""
