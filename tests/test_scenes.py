"""Scene files: the nine packaged scenes, strict validation, overrides, meshes with the paper's counts."""

import re
import textwrap

import numpy as np
import pytest

from solidshell import InputError, meshing, scenes

PAPER_SCENES = [
    "circle-pedestal",
    "hang-100",
    "hang-20",
    "large-square-pedestal",
    "sphere",
    "square-on-disc",
    "square-pedestal",
    "strip-warp",
    "strip-weft",
]


def expected_counts(recipe, density):
    """(nodes, quads) of a recipe mesh, from the structure of each recipe."""
    n = [int(x) for x in density.split("x")]
    if recipe in ("strip", "square"):
        return (n[0] + 1) * (n[1] + 1), n[0] * n[1]
    if recipe == "square_on_square":  # A along the pedestal edge x B outward x 4 panels
        return 4 * n[0] * (n[1] + 1), 4 * n[0] * n[1]
    return (n[0] + 1) * n[1], n[0] * n[1]  # R radial/outward x C around (closed ring)


EXAMPLE_SCENES = ["drape-tester"]


def test_available_is_the_paper_set_and_the_examples():
    assert sorted(p.stem for p in scenes.SCENE_DIR.glob("*.toml")) == PAPER_SCENES
    assert set(EXAMPLE_SCENES) <= {p.stem for p in scenes.EXAMPLE_DIR.glob("*.toml")}
    assert set(PAPER_SCENES) | set(EXAMPLE_SCENES) <= set(scenes.available())


@pytest.mark.parametrize("name", PAPER_SCENES)
def test_scene_loads(name):
    s = scenes.load(name)
    assert s.name == name and s.title and s.paper_section
    assert s.density in s.mesh["paper_meshes"]
    s.material_object()


def test_scene_contents():
    sp = scenes.load("square-pedestal")
    assert sp.recipe == "square_on_square" and sp.geometry["sheet"] == 20.0 and sp.geometry["pedestal"] == 10.0
    assert sp.density == "48x16x4"
    assert sp.mesh["paper_meshes"] == ["24x8x4", "48x16x4", "6x2x4"]
    assert sp.mesh["adaptive_level0"] == "6x2x4"  # 48 quads, Sec. 6.1
    assert sp.supports == {"clamped": ("clamped",)} and sp.solver["kind"] == "static"
    assert sp.solver["relax"] == {"preset": "fast"}
    assert scenes.load("strip-weft").material_object().warp_angle == 90.0
    assert scenes.load("strip-warp").material_object().warp_angle == 0.0
    cp = scenes.load("circle-pedestal")
    assert (cp.geometry["diameter"], cp.geometry["pedestal_diameter"], cp.density) == (25.4, 12.7, "20x80")
    sd = scenes.load("square-on-disc")
    assert (sd.geometry["sheet"], sd.geometry["pedestal_diameter"], sd.density) == (50.0, 20.0, "30x240")
    assert sd.mesh["adaptive_level0"] == "4x32"
    lp = scenes.load("large-square-pedestal")
    assert (lp.geometry["sheet"], lp.geometry["pedestal"], lp.density) == (40.0, 20.0, "45x15x4")
    h20, h100 = scenes.load("hang-20"), scenes.load("hang-100")
    assert (h20.geometry["size"], h20.density, h20.output["snapshots"]) == (20.0, "40x40", [0.0, 0.1, 0.4, 2.1])
    assert (h100.geometry["size"], h100.density, h100.output["snapshots"]) == (100.0, "50x50", [0.0, 0.4, 1.4, 3.0])
    assert h20.supports == {"fixed_translations": ("hung",)} and h20.solver["kind"] == "explicit"
    assert h20.solver_settings()["snapshots"] == [0.0, 0.1, 0.4, 2.1]
    assert h20.solver_settings()["t_end"] == 2.1 and h100.solver_settings()["t_end"] == 3.0
    sph = scenes.load("sphere")
    assert (sph.geometry["size"], sph.density, sph.solver["kind"]) == (30.0, "60x60", "relax")
    assert sph.solver_settings() == {"preset": "fast"}
    assert sph.mesh["adaptive_level0"] == "16x16" and "100x100" in sph.mesh["paper_meshes"]
    (ball,) = sph.contact
    assert ball["type"] == "sphere" and ball["radius"] == 5.0
    assert ball["centre"][2] + ball["radius"] == pytest.approx(-0.0593 / 2)  # top touches the lower face
    assert sph.supports == {"static": {"fixed_x": ("centre",), "fixed_y": ("centre", "centre_east")}}


@pytest.mark.parametrize("name", PAPER_SCENES)
def test_meshes_build_with_paper_counts(name):
    from solidshell.scenes.build import support_mask

    s = scenes.load(name)
    params = {k: v for k, v in s.geometry.items() if k != "recipe"}
    for density in dict.fromkeys([s.density, *s.mesh["paper_meshes"]]):
        m = meshing.build_mesh(s.recipe, density, **params)
        nodes, quads = expected_counts(s.recipe, density)
        assert (m.n_nodes, m.n_quads, m.n_tris) == (nodes, quads, 0), (name, density)
        support_mask(s, m, "static")  # every support set, [supports.static]'s too, exists and is not empty
    m = meshing.build_mesh(s.recipe, s.density, **params)
    if s.recipe == "square_on_square":
        g = s.geometry
        assert m.area() == pytest.approx(g["sheet"] ** 2 - g["pedestal"] ** 2, rel=1e-12)
        assert m.node_set("clamped").size == 4 * int(s.density.split("x")[0])
    if s.recipe == "square":
        assert m.area() == pytest.approx(s.geometry["size"] ** 2, rel=1e-12)
        assert sorted(map(tuple, m.nodes[m.node_set("hung"), :2])) == [
            (-s.geometry["size"] / 2, s.geometry["size"] / 2),
            (s.geometry["size"] / 2, s.geometry["size"] / 2),
        ]
    if s.recipe == "strip":
        assert m.area() == pytest.approx(5.0, rel=1e-12)
        assert np.all(m.nodes[m.node_set("clamped"), 0] == 0.0)


# ----------------------------------------------------------------------------- strict validation
BASE = """
name = "mine"
title = "my sheet"
[geometry]
recipe = "square"
size = 10.0
[mesh]
density = "4x4"
"""


def write(tmp_path, text, name="mine.toml"):
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def test_user_scene_minimal(tmp_path):
    s = scenes.load(write(tmp_path, BASE))
    assert s.name == "mine" and s.density == "4x4" and s.solver["kind"] == "static"
    assert s.loads["gravity"] is True and s.material == {"fabric": "wool"}


@pytest.mark.parametrize(
    "extra, key",
    [
        ("colour = 'red'\n", "colour"),
        ("[meshh]\ndensity='4x4'\n", "meshh"),
        ("[material]\nfabric='wool'\nbending_wrap=0.1\n", "material.bending_wrap"),
        ("[supports]\nclampd='outer'\n", "supports.clampd"),
        ("[loads]\ngravityy=true\n", "loads.gravityy"),
        ("[[contact]]\ntype='sphere'\ncentre=[0,0,-5]\nradius=5\nradiuss=3\n", "contact[0].radiuss"),
        ("[solver]\nkind='static'\nstaticc={}\n", "solver.staticc"),
        ("[output]\npictures=['top']\nmovie=true\n", "output.movie"),
        ("[model]\nthickness='green'\n", "model.thickness"),
    ],
)
def test_unknown_key_names_key_and_file(tmp_path, extra, key):
    text = BASE.replace("[geometry]", extra + "[geometry]") if not extra.startswith("[") else BASE + extra
    p = write(tmp_path, text)
    with pytest.raises(InputError, match=re.escape(f"{p}: {key}: unknown key (allowed here: ")) as e:
        scenes.load(p)
    msg = str(e.value)
    assert key in msg and str(p) in msg and "unknown key" in msg


def test_unknown_geometry_key(tmp_path):
    p = write(tmp_path, BASE.replace("size = 10.0", "size = 10.0\nwidth = 3.0"))
    with pytest.raises(InputError, match=r"geometry\.width.*unknown key"):
        scenes.load(p)


@pytest.mark.parametrize(
    "old, new, key",
    [
        ("size = 10.0", 'size = "ten"', "geometry.size"),
        ("size = 10.0", "size = -1.0", "geometry.size"),
        ('density = "4x4"', "density = 44", "mesh.density"),
        ('title = "my sheet"', "title = 3", "title"),
        ("[mesh]", '[loads]\ngravity = "yes"\n[mesh]', "loads.gravity"),
        ("[mesh]", '[material]\nfabric = "wool"\nthickness = "thin"\n[mesh]', "material.thickness"),
        ("[mesh]", "[supports]\nclamped = 3\n[mesh]", "supports.clamped"),
        ("[mesh]", '[solver]\nkind = "implicit"\n[mesh]', "solver.kind"),
        ("[mesh]", "[output]\nsnapshots = [0.4, 0.1]\n[mesh]", "output.snapshots"),
        ("[mesh]", '[[contact]]\ntype = "sphere"\ncentre = [0, 0]\nradius = 5\n[mesh]', "contact[0].centre"),
        ("[mesh]", '[[contact]]\ntype = "cube"\n[mesh]', "contact[0].type"),
        ('recipe = "square"', 'recipe = "hexagon"', "geometry.recipe"),
    ],
)
def test_wrong_types(tmp_path, old, new, key):
    p = write(tmp_path, BASE.replace(old, new))
    with pytest.raises(InputError, match=re.escape(f"{p}: {key}: ")) as e:  # file: key: what is wrong
        scenes.load(p)
    assert key in str(e.value) and str(p) in str(e.value)


@pytest.mark.parametrize(
    "field, value",
    [("bending_warp", 0.0), ("tensile_weft", -5.0), ("thickness", 0.0), ("weight", -0.019), ("shear", 0)],
)
def test_nonpositive_material(tmp_path, field, value):
    p = write(tmp_path, BASE + f"[material]\nfabric = 'wool'\n{field} = {value}\n")
    with pytest.raises(InputError, match=field):
        scenes.load(p)


def test_isotropic_material(tmp_path):
    s = scenes.load(write(tmp_path, BASE + "[material]\nisotropic = { E = 1e5, nu = 0.3, h = 0.1, density = 1.0 }\n"))
    m = s.material_object()
    assert m.E_z == pytest.approx(1e4)
    with pytest.raises(InputError, match="E"):
        scenes.load(write(tmp_path, BASE + "[material]\nisotropic = { E = 0.0, nu = 0.3, h = 0.1 }\n"))


@pytest.mark.parametrize("density", ["24x8x4", "0x5", "-3x4", "4x", "x4", "four", "4.5x4"])
def test_malformed_density(tmp_path, density):
    with pytest.raises(InputError, match="density"):
        scenes.load(write(tmp_path, BASE.replace('"4x4"', f'"{density}"')))


def test_check_density():
    assert scenes.check_density("48X16×4", "square_on_square") == "48x16x4"
    for bad, words in (
        ("24x8", "'24x8': recipe 'square_on_square' takes 3 counts"),
        ("0x5x4", "'0x5x4': every count must be positive"),
        ("-3x4x4", "'-3x4x4': expected positive integers joined by 'x'"),
        ("", "'': expected positive integers joined by 'x'"),
    ):
        with pytest.raises(InputError, match=re.escape(f"malformed mesh density {words}")):
            scenes.check_density(bad, "square_on_square")


def test_missing_and_broken_files(tmp_path):
    with pytest.raises(InputError, match="unknown scene"):
        scenes.load("no-such-scene")
    with pytest.raises(InputError, match="not found"):
        scenes.load(tmp_path / "absent.toml")
    with pytest.raises(InputError, match="not valid TOML"):
        scenes.load(write(tmp_path, 'name = "x"\ntitle = ['))
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b'name = "\xff\xfe"\n')
    with pytest.raises(InputError, match="UTF-8"):
        scenes.load(binary)
    with pytest.raises(InputError, match="is a directory|not found"):
        scenes.load(str(tmp_path) + "/")
    with pytest.raises(InputError, match="required"):
        scenes.load(write(tmp_path, 'name = "x"\n[geometry]\nrecipe = "square"\nsize = 1.0\n'))


def test_file_geometry_relative_to_scene(tmp_path):
    from solidshell.scenes.build import build_scene_mesh

    m = meshing.build_mesh("square", "3x2", size=6.0)
    sub = tmp_path / "meshes"
    sub.mkdir()
    m.to_meshio().write(sub / "sheet.vtu")
    p = write(
        tmp_path,
        'name = "f"\ntitle = "from file"\n[geometry]\nfile = "meshes/sheet.vtu"\n'
        '[supports]\nfixed_translations = "hung"\n',
    )
    s = scenes.load(p)
    assert s.geometry["file"] == sub / "sheet.vtu"
    mesh, name = build_scene_mesh(s)
    assert (mesh.n_nodes, mesh.n_quads) == (12, 6) and mesh.node_set("hung").size == 2
    with pytest.raises(InputError, match="density"):
        scenes.load(write(tmp_path, 'name = "f"\ntitle = "t"\n[geometry]\nfile = "x.msh"\n[mesh]\ndensity = "4x4"\n'))


def test_component_and_static_supports(tmp_path):
    """fixed_x / _y / _z fix one component of U_o; [supports.static] holds only in a static solve
    (the packaged sphere: its centre in-plane and the next node along +X in y, so the frictionless
    static drape can neither slide nor turn); a missing set there is one InputError naming the key."""
    from solidshell.scenes.build import build_scene_mesh, support_mask

    sph = scenes.load("sphere")
    mesh, _ = build_scene_mesh(sph, "4x4")
    assert not support_mask(sph, mesh).any() and not support_mask(sph, mesh, "relax").any()
    fixed = support_mask(sph, mesh, "static")
    c, e = mesh.node_set("centre")[0], mesh.node_set("centre_east")[0]
    np.testing.assert_array_equal(mesh.nodes[[c, e]], [[0, 0, 0], [7.5, 0, 0]])  # 30 cm / 4
    assert fixed[c].tolist() == [True, True] + [False] * 4 and fixed[e].tolist() == [False, True] + [False] * 4
    assert fixed.sum() == 3
    p = write(tmp_path, BASE + '[supports]\nfixed_z = "corners"\n[supports.static]\nfixed_x = "nowhere"\n')
    sc = scenes.load(p)
    m, _ = build_scene_mesh(sc, "2x2")
    assert support_mask(sc, m)[:, [0, 1, 3, 4, 5]].sum() == 0 and support_mask(sc, m)[:, 2].sum() == 4
    with pytest.raises(InputError, match=r"supports\.static\.fixed_x: .*nowhere"):
        support_mask(sc, m, "static")


# ----------------------------------------------------------------------------- overrides
def test_with_overrides():
    s = scenes.load("square-pedestal")
    t = s.with_overrides(
        {
            "mesh.density": "24x8x4",
            "solver.static.c": 2e-3,
            "material.warp_angle": 90,
            "solver.kind": "relax",
            "solver.relax.alpha": 1.0,
        }
    )
    assert (
        t.density == "24x8x4" and t.solver["static"] == {"sequence": "auto", "c": 2e-3} and t.solver["kind"] == "relax"
    )
    assert t.material_object().warp_angle == 90.0
    assert t.solver_settings() == {"preset": "fast", "alpha": 1.0}
    assert s.density == "48x16x4" and s.solver["static"] == {"sequence": "auto"}  # the original is unchanged
    c = scenes.load("sphere").with_overrides({"contact.0.radius": 6.0})
    assert c.contact[0]["radius"] == 6.0
    assert s.with_overrides({}) is s


@pytest.mark.parametrize(
    "over, match",
    [
        ({"mesh.densty": "24x8x4"}, "mesh.densty"),
        ({"mesh.density": "24x8"}, "density"),
        ({"material.thickness": 0.0}, "thickness"),
        ({"geometry.sheet": "big"}, "geometry.sheet"),
        ({"nonsense": 1}, "nonsense"),
        ({"contact.3.radius": 1.0}, "contact"),
        ({"a..b": 1}, "dotted key"),
    ],
)
def test_bad_overrides(over, match):
    with pytest.raises(InputError, match=match):
        scenes.load("square-pedestal").with_overrides(over)


def test_parse_overrides():
    assert scenes.parse_overrides(
        [
            "solver.static.c=2e-3",
            "mesh.density=24x8x4",
            "loads.gravity=false",
            "output.snapshots=[0, 0.5]",
            'name="x y"',
        ]
    ) == {
        "solver.static.c": 2e-3,
        "mesh.density": "24x8x4",
        "loads.gravity": False,
        "output.snapshots": [0, 0.5],
        "name": "x y",
    }
    with pytest.raises(InputError, match="key=value"):
        scenes.parse_overrides(["solver.static.c"])
