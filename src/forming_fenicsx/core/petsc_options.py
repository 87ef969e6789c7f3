"""PETSc options of one solver under a named prefix (``flow_``, ``normal_stress_filter_``), so that
a user can address each solver's options (e.g. ``-flow_ksp_view`` on the command line)."""
from __future__ import annotations

from typing import Any

from petsc4py import PETSc


class PrefixedOptions:
    """Options set under ``name_`` (``name2_``, ... while another live solver holds that prefix) and
    removed by ``release``: PETSc's options database holds 512 entries, and every run would
    otherwise leave its own there. The prefix stays held until release, since some options (MUMPS'
    ICNTL) are read only at the first factorisation."""

    _live: set[str] = set()

    def __init__(self, name: str, options: dict[str, Any]):
        prefix, count = f"{name}_", 1
        while prefix in self._live:
            count += 1
            prefix = f"{name}{count}_"
        self._live.add(prefix)
        self.prefix = prefix
        self._names = [prefix + key for key in options]
        database = PETSc.Options()
        for key, value in options.items():
            database[prefix + key] = value

    def release(self) -> None:
        database = PETSc.Options()
        for name in self._names:
            database.delValue(name)
        self._live.discard(self.prefix)
