"""The import rule of the package's layers: each subpackage imports only from the layers below it
(and from its own, without a circle), counting the imports inside functions too. The layers, from
the bottom: core, physics, config, mesh, fem, coupled, solvers, post, io, verification, app; data
flows up the same way (scene -> mesh -> forms -> solvers -> post-processing -> files)."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "forming_fenicsx"
LAYERS = ("core", "physics", "config", "mesh", "fem", "coupled", "solvers", "post", "io",
          "verification", "app")


def modules() -> dict[str, Path]:
    """Every module of the package by its dotted name below forming_fenicsx."""
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        found[".".join(parts)] = path
    return found


def imports(name: str, path: Path) -> set[str]:
    """The package's modules (and subpackages) that ``name`` imports anywhere in it, absolute or
    relative: importing a.b.c imports the packages a and a.b too, but for the packages that hold
    ``name`` itself (Python has imported them first)."""
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    dotted = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            dotted += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                kept = package[:len(package) - node.level + 1]
                base = ".".join(["forming_fenicsx", *kept] + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            dotted += [base] + [f"{base}.{alias.name}" for alias in node.names]
    known, found = modules(), set()
    for target in dotted:
        if target != "forming_fenicsx" and not target.startswith("forming_fenicsx."):
            continue
        parts = target.removeprefix("forming_fenicsx.").split(".")
        found.update(".".join(parts[:end]) for end in range(1, len(parts) + 1))
    ancestors = {".".join(name.split(".")[:end]) for end in range(1, name.count(".") + 1)}
    return {t for t in found if t in known and t != name and t not in ancestors}


def layer(name: str) -> int | None:
    """The layer index of a module (None for the package's face, forming_fenicsx itself)."""
    top = name.split(".")[0]
    return LAYERS.index(top) if top in LAYERS else None


GRAPH = {name: imports(name, path) for name, path in modules().items()}


def test_every_module_lives_in_a_layer():
    outside = [name for name in GRAPH if name and layer(name) is None]
    assert outside == []


def test_no_module_imports_from_a_layer_above_its_own():
    upward = sorted(f"{name} -> {target}" for name, targets in GRAPH.items() if name
                    for target in targets if layer(target) is not None
                    and layer(target) > layer(name))
    assert upward == []


def test_no_circle_of_imports():
    """Depth-first search for a cycle among the modules (subpackages' faces included)."""
    state: dict[str, int] = {}
    circles = []

    def visit(name: str, trail: list[str]) -> None:
        state[name] = 1
        for target in sorted(GRAPH.get(name, ())):
            if state.get(target) == 1:
                circles.append(" -> ".join(trail[trail.index(target):] + [target]))
            elif target not in state:
                visit(target, trail + [target])
        state[name] = 2

    for name in GRAPH:
        if name not in state:
            visit(name, [name])
    assert circles == []


@pytest.mark.parametrize("text, expected", [
    ("from forming_fenicsx.core.errors import SceneError", {"core", "core.errors"}),
    ("def f():\n    from forming_fenicsx.app import run\n", {"app", "app.run"}),
    ("from ..fem.forms import FlowProblem", {"fem", "fem.forms"}),
    ("import math\nfrom .coordinates import CoordinateSystem", {"physics.coordinates"}),
])
def test_the_rule_reads_imports_inside_functions_and_relative_ones(tmp_path, text, expected):
    path = tmp_path / "probe.py"
    path.write_text(text)
    assert imports("physics.probe", path) - {"physics"} == expected
