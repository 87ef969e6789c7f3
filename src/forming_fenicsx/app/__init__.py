"""The commands: one run end to end, `forming` (run, mesh, study, bench), design and speed-accuracy
studies, benchmarks.
"""
