"""`forming study`: a grid of runs of one scene over varied keys, each with its quantities and cost.

Two kinds of study, told apart by the varied keys:
- a speed-accuracy study varies numerical keys only (sections discretisation, solver, penalty,
  output): each quantity's error is taken against the exact value where one is known (Hill's ram
  pressure for frictionless Example 1 geometry at reduction 1/2, Hill's drawing field), otherwise
  against a Richardson extrapolation from the three finest mesh sizes of the same other settings;
  the report lists the runs by wall time and the cheapest setting per error level;
- a design study varies at least one physical key (process, geometry, material, friction): the
  report lists the runs in parameter order, each quantity is plotted against the first design key
  (one line per setting of the other keys) and an interior minimum is located by a parabola through
  the least value and its two neighbours. Error columns and the cheapest settings appear only where
  a reference exists (with the mesh varied too: Richardson per design point).
A study stopped and started again skips the runs its study.json already holds.
"""
from __future__ import annotations
from forming_fenicsx.app.study.analysis import (ERROR_LEVELS, MESH_KEYS, QUANTITIES, cheapest,
                                                exact_value, find_optima, interior_minimum,
                                                is_design_key, positions, references,
                                                relative_error, series, value)
from forming_fenicsx.app.study.grid import (load_study, parse_quantities, parse_vary, run_folder,
                                            run_study, solve_scene, study_scenes)
from forming_fenicsx.app.study.report import report

__all__ = ["ERROR_LEVELS", "MESH_KEYS", "QUANTITIES", "cheapest", "exact_value", "find_optima",
           "interior_minimum", "is_design_key", "load_study", "parse_quantities",
           "parse_vary", "positions", "references", "relative_error", "report", "run_folder",
           "run_study", "series", "solve_scene", "study_scenes", "value"]
