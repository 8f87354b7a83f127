"""The scene schema (solidshell/scenes/schema.py): every error is one line ``FILE: dotted.key: what``,
with array indices as ``[i]`` and the tags of the contact/geometry/material unions left out of the key;
the vocabularies are the ones of the modules that define them."""

import re
import textwrap

import pytest

from solidshell import InputError, meshing, plotting, scenes
from solidshell.elements import THICKNESS_STRAINS
from solidshell.elements.quad4 import MEMBRANES

BASE = """
name = "mine"
title = "my sheet"
[geometry]
recipe = "square"
size = 10.0
[mesh]
density = "4x4"
"""


def load(tmp_path, extra="", replace=("", "")):
    p = tmp_path / "mine.toml"
    p.write_text(textwrap.dedent(BASE.replace(*replace) + extra))
    return p, (lambda: scenes.load(p))


@pytest.mark.parametrize(
    "extra, replace, message",
    [
        # the key inside a contact body, not "contact.0.sphere.radius"
        (
            "[[contact]]\ntype='sphere'\ncentre=[0,0,0]\nradius=0\n",
            None,
            "contact[0].radius: must be positive, got 0.0",
        ),
        ("[[contact]]\nradius=5\n", None, "contact[0].type: required key is missing (sphere, plane, pedestal or mesh)"),
        ("[[contact]]\ntype=3\n", None, "contact[0].type: must be a string, got integer 3"),
        (
            "[[contact]]\ntype='pedestal'\nshape='disc'\ndiameter=3\nsize=3\n",
            None,
            "contact[0].size: does not apply to a disc pedestal",
        ),
        (
            "[[contact]]\ntype='plane'\npoint=[0,0,0]\nnormal=[0,0,0]\n",
            None,
            "contact[0].normal: must be a non-zero vector",
        ),
        ("", ("[geometry]", "contact = [3]\n[geometry]"), "contact[0]: must be a table, got integer 3"),
        # element of a vector, of an array of tables, of a nested solver table
        (
            "[loads]\ngravity_direction=[0,'a',0]\n",
            None,
            "loads.gravity_direction[1]: must be a number, got string 'a'",
        ),
        (
            "[[loads.point]]\nnode_set='a'\nat=[0,0,0]\nforce=[0,0,1]\n",
            None,
            "loads.point[0]: give exactly one of 'node_set' or 'at'",
        ),
        ("[solver.static]\nx={a=[1, {b=inf}]}\n", None, "solver.static.x.a[1].b: must be finite, got inf"),
        ("[output]\nsnapshots=[0, 'a']\n", None, "output.snapshots[1]: must be a number, got string 'a'"),
        (
            "[output]\npictures=['top', 'front']\n",
            None,
            f"output.pictures[1]: unknown view 'front' (known: {', '.join(plotting.VIEWS)})",
        ),
        # the material union: a rigidity refused by the section itself, keys of the isotropic table
        (
            "[material]\nbending_weft=0.0\n",
            None,
            "material: bending_weft must be positive and finite [gf*cm^2/cm], got 0.0",
        ),
        ("[material]\nisotropic={E=1e5, nu=0.3}\n", None, "material.isotropic.h: required key is missing"),
        (
            "[material]\nfabric='wool'\nisotropic={E=1e5, nu=0.3, h=0.1}\n",
            None,
            "material.fabric: unknown key (allowed here: isotropic)",
        ),
        # the geometry union: recipes and their lengths from solidshell.meshing.RECIPES
        (
            "",
            ('recipe = "square"', 'recipe = "from_file"'),
            "geometry.recipe: unknown recipe 'from_file' (known: disc_on_disc, square, square_on_disc, square_on_square, strip)",
        ),
        (
            "",
            ('recipe = "square"\nsize = 10.0', 'recipe = "strip"\nlength = 5.0'),
            "geometry.width: required by recipe 'strip' [cm]; missing",
        ),
        (
            "",
            ("size = 10.0", 'size = 10.0\nfile = "a.msh"'),
            "geometry: give exactly one of 'recipe' (a built-in mesh recipe) or 'file' (a .msh/.geo file)",
        ),
        (
            "",
            ('"4x4"', '"4x4x4"'),
            "mesh.density: malformed mesh density '4x4x4': recipe 'square' takes 2 counts, e.g. '20x80'",
        ),
        (
            "paper_meshes = ['4x4', '4x']\n",
            None,
            "mesh.paper_meshes[1]: malformed mesh density '4x': expected positive integers joined by 'x', e.g. '48x16x4'",
        ),
        # tables with their own settings models keep those models' words
        ("[adapt]\nlevels=0\n", None, "adapt: setting levels = 0: Input should be greater than or equal to 1"),
        ("[perturbation]\nshape='x'\n", None, "perturbation: setting shape = 'x': Input should be 'random' or 'folds'"),
        # a typo is named before the missing key it causes
        ("", ('title = "my sheet"', 'titel = "my sheet"'), "titel: unknown key (allowed here: "),
    ],
)
def test_one_line_names_file_and_key(tmp_path, extra, replace, message):
    p, go = load(tmp_path, extra, replace or ("", ""))
    with pytest.raises(InputError, match="^" + re.escape(f"{p}: {message}")) as e:
        go()
    assert "\n" not in str(e.value)


def test_tables_become_the_scene_fields(tmp_path):
    p, go = load(
        tmp_path,
        "[[contact]]\ntype='pedestal'\nshape='disc'\ndiameter=10\n"
        "[[loads.point]]\nat=[1,2,3]\nforce=[0,0,1]\n"
        "[supports]\nclamped=['a','b']\n[solver.relax]\npreset='fast'\n"
        "[perturbation]\nshape='folds'\namplitude=0.5\nfolds=6\n",
    )
    s = go()
    # the table as written; Scene.bodies() fills the rest: outside a pedestal recipe, 10 cm high,
    # centre at the origin, offset 0, solid, sharp edge, frictionless
    assert s.contact == ({"type": "pedestal", "shape": "disc", "diameter": 10.0},)
    assert s.bodies() == [
        {
            "type": "pedestal",
            "shape": "disc",
            "diameter": 10.0,
            "centre": (0.0, 0.0, 0.0),
            "height": 10.0,
            "edge_radius": 0.0,
            "offset": 0.0,
            "friction": 0.0,
            "support": "solid",
            "role": "support",
            "origin": "contact[0]",
        }
    ]
    assert s.loads["point"] == [{"force": (0.0, 0.0, 1.0), "at": (1.0, 2.0, 3.0)}]
    assert s.supports == {"clamped": ("a", "b")}
    assert s.solver == {"kind": "static", "static": {}, "explicit": {}, "relax": {"preset": "fast"}}
    assert s.perturbation["folds"] == 6 and s.perturbation["amplitude"] == 0.5 and "seed" in s.perturbation
    assert s.model == {"thickness_strain": "green", "mu": 0.5, "membrane": "full"}


def test_vocabularies_are_those_of_their_modules(tmp_path):
    for ts in THICKNESS_STRAINS:
        for mb in MEMBRANES:
            _, go = load(tmp_path, f"[model]\nthickness_strain='{ts}'\nmembrane='{mb}'\n")
            assert (go().model["thickness_strain"], go().model["membrane"]) == (ts, mb)
    p, go = load(tmp_path, "[model]\nmembrane='eas'\n")
    with pytest.raises(InputError, match=re.escape(f"{p}: model.membrane: must be 'full' or 'ans', got 'eas'")):
        go()
    square_on_square = meshing.RECIPES["square_on_square"]
    assert square_on_square.required == ("sheet", "pedestal") and "grading" in square_on_square.geometry


def test_override_sets_list_items_and_refuses_bad_paths():
    sph = scenes.load("sphere")
    assert sph.with_overrides({"contact.0.radius": 6.0}).contact[0]["radius"] == 6.0
    with pytest.raises(InputError, match=re.escape("override 'contact.x.radius': contact.x is not an index")):
        sph.with_overrides({"contact.x.radius": 6.0})
    with pytest.raises(InputError, match=re.escape("override 'mesh.density.x': the parent is not a table")):
        sph.with_overrides({"mesh.density.x": 1})
    with pytest.raises(InputError, match=re.escape("(with overrides): contact[0].radius: must be positive, got -6.0")):
        sph.with_overrides({"contact.0.radius": -6.0})
