"""Files and figures: summary.json, history.csv, die and exit profiles, fields.xdmf, velocity.npz,
and the PNG figures.
"""
