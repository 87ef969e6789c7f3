"""Every demo script imports names the package has, and every demo scene and study loads: a moved
or renamed name, or a scene key a change refused, fails here rather than in a user's hands (the
scripts themselves run in the tests that use their results and in the docs' measurements)."""
from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

from forming_fenicsx.app.study import load_study
from forming_fenicsx.config.loader import load_scene

DEMOS = Path(__file__).resolve().parents[1] / "demos"
# every script but ParaView's (it runs in pvpython and imports nothing of the package)
SCRIPTS = [path for path in sorted(DEMOS.glob("*.py")) if path.name != "paraview_open.py"] + [
    DEMOS.parent / "scripts" / "demo-numbers"]


@pytest.mark.no_parallel_content  # pure Python: reading files
@pytest.mark.parametrize("script", SCRIPTS, ids=lambda path: path.name)
def test_a_demo_script_imports_names_the_package_has(script):
    imported = 0
    for node in ast.walk(ast.parse(script.read_text())):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("forming_fenicsx"):
            module = importlib.import_module(node.module)
            for alias in node.names:
                assert hasattr(module, alias.name) or importlib.util.find_spec(
                    f"{node.module}.{alias.name}") is not None, f"{node.module}.{alias.name}"
                imported += 1
    assert imported > 0


@pytest.mark.no_parallel_content  # pure Python: reading scenes
@pytest.mark.parametrize("scene", sorted(DEMOS.glob("*.toml")), ids=lambda path: path.name)
def test_a_demo_scene_or_study_loads(scene):
    if scene.name.endswith(".study.toml"):
        data, vary, _ = load_study(scene)
        assert vary and data["process"]["kind"] in ("drawing", "extrusion")
    else:
        assert load_scene(scene).process.velocity > 0
