"""FFCx's lookup of a compiled form in its cache by the module's exact file name.

FFCx (0.5 and 0.9 alike) finds a cached module with an ``importlib.machinery.FileFinder`` whose
caches it invalidates first, so every form compiled lists the whole cache directory: with the
~13k files a developer's cache holds, 58 lookups of a 2D run took 0.48 s of its 1.8 s
(docs/accuracy.md, start-up). ``exact_lookup`` replaces the lookup, while a command runs, by one
that opens ``<cache>/<module><suffix>`` for the interpreter's extension suffixes: the same module,
the same wait for a compilation in another process, no listing.
"""
from __future__ import annotations

import importlib.machinery
import importlib.util
import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


def _compiled_file(cache_dir: Path, module_name: str) -> Path | None:
    """The module's extension file in the cache, if there is one."""
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        path = cache_dir / (module_name + suffix)
        if path.is_file():
            return path
    return None


def get_cached_module(module_name: str, object_names: list[str], cache_dir: str | Path,
                      timeout: int) -> tuple[Any, Any]:
    """FFCx's get_cached_module (same arguments and results): (None, None) after creating the C
    file when this process is to compile the module, else the compiled objects and module once
    the ``.c.cached`` marker of the compiling process appears (waiting up to ``timeout`` s)."""
    cache_dir = Path(cache_dir)
    c_filename = cache_dir.joinpath(module_name).with_suffix(".c")
    ready_name = c_filename.with_suffix(".c.cached")
    cache_dir.mkdir(exist_ok=True, parents=True)
    try:
        with open(c_filename, "x"):
            return None, None
    except FileExistsError:
        pass
    for _ in range(timeout):
        if os.path.exists(ready_name):
            path = _compiled_file(cache_dir, module_name)
            if path is None:
                raise ModuleNotFoundError(f"Unable to find JIT module {module_name} in {cache_dir}")
            loader = importlib.machinery.ExtensionFileLoader(module_name, str(path))
            spec = importlib.util.spec_from_file_location(module_name, path, loader=loader)
            module = importlib.util.module_from_spec(spec)
            loader.exec_module(module)
            return [getattr(module.lib, name) for name in object_names], module
        time.sleep(1)
    raise TimeoutError(f"JIT compilation timed out, probably due to a failed previous compile. "
                       f"Try cleaning cache (e.g. remove {c_filename}) or increase timeout.")


@contextmanager
def exact_lookup() -> Iterator[None]:
    """FFCx looks up cached forms by exact file name inside the block; its own lookup after
    (imported here: a command that compiles nothing does not pay for FFCx)."""
    import ffcx.codegeneration.jit as ffcx_jit

    original = ffcx_jit.get_cached_module
    ffcx_jit.get_cached_module = get_cached_module
    try:
        yield
    finally:
        ffcx_jit.get_cached_module = original
