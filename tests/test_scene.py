"""Scene loading: defaults, overrides, and one clear message naming the key for every bad value."""
from pathlib import Path

import pytest
from mpi4py import MPI

from forming_fenicsx.app.cli import main, petsc_options_from_args
from forming_fenicsx.core.errors import SceneError
from forming_fenicsx.config.loader import load_scene, scene_from_dict

RANK = MPI.COMM_WORLD.rank
DEMOS = Path(__file__).parents[1] / "demos"


def test_defaults_are_the_papers_example1():
    scene = scene_from_dict({"process": {"kind": "extrusion"}})
    assert (scene.geometry.length, scene.geometry.entry_thickness,
            scene.geometry.exit_thickness) == (20, 10, 5)
    assert scene.material.A == pytest.approx(3**0.5)
    assert (scene.material.alpha, scene.material.rate1, scene.material.rate2) == (1e-3, 1e-3, 1e3)
    # The default penalties are relative to the scene's scales (docs/penalties.md)
    rate, stress = scene.scales.strain_rate, scene.scales.flow_stress
    assert ((scene.scales.velocity, scene.scales.length) == (1.0, 10.0)
            and rate == pytest.approx(0.1))
    assert stress == pytest.approx(scene.material.flow_stress(rate))
    assert scene.penalty.d == pytest.approx(1e-4 * rate / stress, rel=1e-12)
    assert scene.penalty.d_N == pytest.approx(1e-3 / stress, rel=1e-12)
    assert scene.friction.d_T == pytest.approx(1e-6) and scene.penalty.augmented
    assert (scene.discretisation.element,
            scene.discretisation.volumetric_integration) == ("Q2", "reduced")
    assert scene.solver.tolerance == 1e-4


def test_demo_scenes_load():
    assert load_scene(DEMOS / "example1_extrusion.toml").friction.mu == 0.0
    assert load_scene(DEMOS / "example1_extrusion_mu01.toml").friction.mu == 0.1


def test_overrides_take_toml_values_and_bare_strings():
    scene = load_scene(DEMOS / "example1_extrusion.toml",
                       ["friction.mu=0.25", "discretisation.element=Q1",
                        "solver.petsc_options.ksp_type=cg"])
    assert scene.friction.mu == 0.25
    assert scene.discretisation.element == "Q1"
    assert scene.solver.petsc_options["ksp_type"] == "cg"


def test_another_material_replaces_the_material_section():
    """--set material.name (or .law) to another material drops the scene's own material keys (the
    strip's piecewise_power A would be refused beside a named material); the material.* overrides
    given with it apply; the same name or law keeps the section."""
    strip = DEMOS / "strip_mm.toml"
    scene = load_scene(strip, ["material.name=aluminium_1100_O", "material.rate_factor=power",
                               "material.m=0.05"])
    assert (scene.material.law, scene.material.K, scene.material.m) == ("hollomon", 180.0, 0.05)
    scene = load_scene(strip, ["material.law=hollomon", "material.K=300", "material.n=0.25"])
    assert (scene.material.K, scene.material.n) == (300.0, 0.25)
    assert load_scene(strip, ["material.law=piecewise_power", "material.A=250"]).material.A == 250.0
    with pytest.raises(SceneError) as error:  # no law left: the replaced section is checked
        load_scene(strip, ["material.law=hollomon"])
    assert error.value.key.startswith("material")


def test_petsc_options_merge_over_the_default_table():
    scene = load_scene(DEMOS / "example1_extrusion.toml",
                       ["solver.petsc_options.mat_mumps_icntl_7=5"])
    assert scene.solver.petsc_options == {"ksp_type": "preonly",
                                          "pc_factor_mat_solver_type": "mumps",
                                          "mat_mumps_icntl_7": 5}
    scene = load_scene(DEMOS / "example1_extrusion.toml", ["solver.petsc_options.pc_type=cholesky"])
    assert scene.solver.petsc_options["pc_type"] == "cholesky"
    assert scene.solver.petsc_options["pc_factor_mat_solver_type"] == "mumps"


BAD = [
    ({"geometry": {"entry_thickness": 0.0}}, "geometry.entry_thickness", "> 0"),
    ({"geometry": {"exit_thickness": 10.0}}, "geometry.exit_thickness", "must be <"),
    ({"geometry": {"exit_thickness": 12.0}}, "geometry.exit_thickness", "reduce"),
    ({"geometry": {"die_position": 25.0, "length": 20.0}}, "geometry.die_position",
     "geometry.length"),
    ({"friction": {"mu": -0.1}}, "friction.mu", ">= 0"),
    ({"friction": {"m": 0.5}}, "friction.m", 'set friction.law = "factor"'),
    ({"friction": {"law": "sticking", "mu": 0.3}}, "friction.mu", "it has no coefficient"),
    ({"friction": {"law": "factor", "m": 1.0, "mu": 0.3}}, "friction.mu", "m is its coefficient"),
    # sticking is rolling's: extrusion's ram face meets the container wall (Example 1 with it:
    # a ram pressure of 6955 k)
    ({"friction": {"law": "sticking"}}, "friction.law", "rolling's only"),
    ({"friction": {"law": "slip"}}, "friction.law", "coulomb, factor, sticking"),
    ({"friction": {"d_T": 0.0}}, "friction.d_T", "> 0"),
    ({"penalty": {"d": 0.0}}, "penalty.d", "> 0"),
    ({"penalty": {"d_N": -1e-6}}, "penalty.d_N", "> 0"),
    ({"solver": {"tolerance": 0.0}}, "solver.tolerance", "(0, 1)"),
    ({"solver": {"method": "bfgs"}}, "solver.method", "direct, modified, newton"),
    ({"solver": {"method": "newton"}, "discretisation": {"averaging": "nodes"}}, "solver.method",
     'averaging = "quadrature"'),
    ({"solver": {"secant_start": -1}}, "solver.secant_start", "integer >= 0"),
    ({"solver": {"dual_start": 1.5}}, "solver.dual_start", "[0, 1]"),
    ({"solver": {"max_iterations": 0}}, "solver.max_iterations", ">= 1"),
    ({"solver": {"max_iterations": 2.5}}, "solver.max_iterations", "an integer"),
    ({"material": {"alpha": 1.5}}, "material.alpha", "(2.10)"),
    ({"material": {"law": "rate_power", "n": 2.0}}, "material.n", "(2.10)"),
    ({"material": {"law": "rate_power", "alpha": 0.5}}, "material.alpha", "unknown key"),
    ({"material": {"law": "zerilli"}}, "material.law", "piecewise_power, rate_power, hollomon"),
    ({"material": {"law": "power", "A": 500.0, "n": 0.2}}, "material.law", "is now \"rate_power\""),
    ({"material": {"name": "copper_annealed"}}, "material.name", "units.stress"),
    ({"material": {"law": "hollomon", "K": 315.0, "n": 1.5}}, "material.n", "Hollomon"),
    ({"material": {"law": "voce", "initial": 100.0, "saturation": 50.0, "scale": 0.2}},
     "material.saturation", ">= material.initial"),
    ({"material": {"law": "swift", "K": 100.0, "n": 0.2, "prestrain": 0.01,
                   "rate_factor": "power"}},
     "material.m", "(0, 1]"),
    ({"material": {"law": "swift", "K": 100.0, "n": 0.2, "prestrain": 0.01, "C": 0.1}},
     "material.C", "does not apply"),
    # a key of the other die (a new user's wedge extrusion without geometry.die)
    ({"geometry": {"die_angle": 45.0}}, "geometry.die_angle", "set geometry.die = 'conical'"),
    # a new user's square bar (the mission's "square sections"): the rectangle named
    ({"geometry": {"symmetry": "3d", "section": "square"}}, "geometry.section",
     'a square bar is a rectangle: section = "rectangle" with entry_width = entry_height'),
    ({"discretisation": {"element": "Q3"}}, "discretisation.element", "Q1, Q2"),
    ({"discretisation": {"mesh_size": 3.0}}, "discretisation.mesh_size", "thinnest"),
    ({"discretisation": {"corner_grading": 0.5}}, "discretisation.corner_grading", "[1, 1000]"),
    ({"penalty": {"d": "small"}}, "penalty.d", "a number"),
    ({"penalty": {"d": True}}, "penalty.d", "a number"),
    ({"process": {"velocity": float("nan")}}, "process.velocity", "finite"),
    ({"process": {"colour": "red"}}, "process.colour", "unknown key"),
    ({"processes": {}}, "processes", "unknown section"),
    ({"process": {"kind": "forging"}}, "process.kind", "extrusion"),
    ({"process": {"kind": "drawing"}, "geometry": {"die_angle": 0.0}},
     "geometry.die_angle", "(0, 90)"),
    ({"process": {"kind": "drawing"}, "geometry": {"die_angle": 90.0}},
     "geometry.die_angle", "(0, 90)"),
    # a new user's flat extrusion die given as a 90 degree cone: the square die named
    ({"process": {"kind": "extrusion"}, "geometry": {"die": "conical", "die_angle": 90.0}},
     "geometry.die_angle", 'a flat die face is geometry.die = "square"'),
    # a new user's wire without its symmetry: the one a diameter belongs to named
    ({"process": {"kind": "drawing"}, "geometry": {"entry_diameter": 3.0, "exit_diameter": 2.6}},
     "geometry.entry_diameter", 'a diameter is given with geometry.symmetry = "axisymmetric"'),
    ({"process": {"kind": "drawing"}, "geometry": {"land_length": -0.1}},
     "geometry.land_length", ">= 0"),
    ({"process": {"kind": "drawing"}, "geometry": {"land_length": 9.0, "length": 7.8}},
     "geometry.land_length", "end before"),
    ({"process": {"kind": "drawing"}, "geometry": {"exit_thickness": 1.625}},
     "geometry.exit_thickness", "reduce"),
    ({"process": {"kind": "drawing"}, "friction": {"mollification_length": 0.0}},
     "friction.mollification_length", "> 0"),
    ({"process": {"kind": "drawing"}, "friction": {"normal_stress": "nodal"}},
     "friction.normal_stress", "averaged"),
    ({"process": {"kind": "drawing", "drive": "shove"}}, "process.drive", "push, pull"),
    ({"solver": {"force_tolerance": 2.0}}, "solver.force_tolerance", "[0, 1)"),
    ({"output": {"die_pressure": "mean"}}, "output.die_pressure", "penalty, stress"),
]


@pytest.mark.parametrize("sections, key, phrase", BAD, ids=[b[1] for b in BAD])
def test_invalid_values_name_the_key(sections, key, phrase):
    data = {"process": {"kind": "extrusion"}}
    for name, values in sections.items():
        data.setdefault(name, {}).update(values)
    with pytest.raises(SceneError) as error:
        scene_from_dict(data)
    assert error.value.key == key
    assert phrase in error.value.message


def test_drawing_defaults_are_the_papers_example2():
    scene = load_scene(DEMOS / "example2_drawing.toml")
    assert scene.process.velocity == 1000.0 and scene.geometry.die_angle == 6.0
    assert scene.material.A == pytest.approx(100 * 3**0.5)
    assert (scene.penalty.d, scene.penalty.d_N, scene.friction.d_T) == (0.005, 0.01, 1e-6)
    assert not scene.penalty.augmented  # the paper's pure penalty contact
    assert scene_from_dict({"process": {"kind": "drawing"}}).discretisation.element == "Q2"
    assert [load_scene(DEMOS / f"example2_drawing{s}.toml").friction.mu
            for s in ("", "_mu02", "_mu04")] == [0.0, 0.2, 0.4]


def test_missing_process_kind():
    with pytest.raises(SceneError) as error:
        scene_from_dict({"geometry": {"length": 20.0}})
    assert error.value.key == "process.kind"


def test_cli_rejects_bad_scene_before_meshing(tmp_path, capsys):
    scene = tmp_path / "bad.toml"
    scene.write_text('[process]\nkind = "extrusion"\n[geometry]\nexit_thickness = 11.0\n')
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    if RANK == 0:  # the message is printed once, by rank 0
        assert "geometry.exit_thickness" in err and "Traceback" not in err
    assert not out.exists()


def test_cli_rejects_bad_override_and_toml(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(DEMOS / "example1_extrusion.toml"), "--out", str(out),
                 "--set", "penalty.dd=1"]) == 2
    assert "penalty.dd" in capsys.readouterr().err or RANK != 0
    broken = tmp_path / "broken.toml"
    broken.write_text("[process\nkind = 1\n")
    assert main(["run", str(broken), "--out", str(out)]) == 2
    assert "not valid TOML" in capsys.readouterr().err or RANK != 0
    assert not out.exists()


def test_petsc_options_from_command_line():
    assert petsc_options_from_args(["-ksp_type", "preonly", "-ksp_view",
                                    "-mat_mumps_icntl_14", "-50"]) == {
        "ksp_type": "preonly", "ksp_view": "", "mat_mumps_icntl_14": "-50"}
    with pytest.raises(SceneError):
        petsc_options_from_args(["ksp_type"])


def test_a_hardening_scene_defaults_to_newton_at_the_integration_points():
    """docs/hardening.md: the secant methods took 18 to 933 linear solves on the hardening demos
    where Newton took 11 to 15; a hardening scene without a [solver] method gets Newton and the
    quadrature averaging, one that names its method keeps it, and a rate law keeps the paper's."""
    hardening = {"process": {"kind": "drawing"}, "units": {"stress": "MPa", "length": "mm"},
                 "material": {"name": "copper_annealed"}}
    scene = scene_from_dict(hardening)
    assert (scene.solver.method, scene.discretisation.averaging) == ("newton", "quadrature")
    named = scene_from_dict({**hardening, "solver": {"method": "direct"}})
    assert (named.solver.method, named.discretisation.averaging) == ("direct", "quadrature")
    rate = scene_from_dict({"process": {"kind": "drawing"}})
    assert (rate.solver.method, rate.discretisation.averaging) == ("modified", "nodes")
