"""Post-processing of a converged (or last) iterate: forces, die and product quantities, heat,
sections, streamlines, the output fields, the summary's numbers and their sanity checks.
"""
