"""Every pedestal a scene draws is a contact body (issue 36): ``Scene.bodies()`` is the one list the
solvers build their bodies from and the pictures draw; the paper's pedestal scenes lie on a solid
pedestal by default (``geometry.pedestal_contact = false`` leaves it out); a Cusick-type support is a
disc on a stem (one compiled body, kernel code CUSICK) with an optional clamp (docs/contact.md, 12)."""

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from solidshell import InputError, scenes
from solidshell.contact import CusickSupport, Pedestal, Sphere
from solidshell.render import bodies_of
from solidshell.render.geometry import pedestal_surfaces
from solidshell.scenes.build import build_scene_mesh, check_initial_contact, contact_bodies, support_mask

H = 0.0593  # wool's thickness (paper, Table 1) [cm]

# the paper's pedestal scenes: (shape, extent key, extent [cm]) of the pedestal (Secs. 3.2-3.5)
PAPER = {
    "square-pedestal": ("square", "size", 10.0),
    "circle-pedestal": ("disc", "diameter", 12.7),
    "square-on-disc": ("disc", "diameter", 20.0),
    "large-square-pedestal": ("square", "size", 20.0),
}
# their height: as long as the skirt can hang (the sheet's half diagonal or radius, at least 10 cm)
HEIGHT = {"square-pedestal": 14.142, "circle-pedestal": 12.7, "square-on-disc": 35.355, "large-square-pedestal": 28.284}

# a support disc Ø20 (the recipe's) 0.4 cm thick on a Ø6 stem, with a Ø16 x 0.5 cm clamp
CUSICK = """
[[contact]]
type = "pedestal"
support = "cusick"
disc_thickness = 0.4
stem_diameter = 6.0
clamp_diameter = 16.0
clamp_thickness = 0.5
"""


def _scene_file(tmp_path, extra="", base="square-on-disc", name="mine"):
    """A copy of a packaged scene with ``extra`` appended (a user's scene file)."""
    text = (scenes.SCENE_DIR / f"{base}.toml").read_text().replace(f'name = "{base}"', f'name = "{name}"')
    p = tmp_path / f"{name}.toml"
    p.write_text(text + extra)
    return p


@pytest.mark.parametrize("name", sorted(PAPER))
def test_paper_pedestal_scenes_lie_on_a_solid_pedestal(name):
    shape, key, extent = PAPER[name]
    sc = scenes.load(name)
    want = {
        "type": "pedestal",
        "shape": shape,
        key: extent,
        "centre": (0.0, 0.0, -H / 2),  # top face h/2 under the mid-surface (z = 0) ...
        "height": HEIGHT[name],
        "edge_radius": 0.0,
        "offset": H / 2,  # ... kept h/2 off it: the lower face on the top, the rim at gap 0
        "friction": 0.0,
        "support": "solid",
        "role": "support",
        "origin": "geometry.recipe",
    }
    assert sc.contact == () and sc.bodies() == [want]
    assert sc.pedestal() == want  # pictures, the DC's pedestal area, the perturbation's centre
    (body,) = contact_bodies(sc)
    assert isinstance(body, Pedestal) and body.offset == H / 2 and body.friction == 0.0
    assert body.height == HEIGHT[name] and body.edge_radius == 0.0
    # the sheet's flat mid-surface: on the rim exactly at gap 0 (round-off of the +-h/2 sums:
    # 1e-15 cm), a point above the top's centre 1 cm off, one 1 cm outside a side 1 cm below the
    # sheet 1 cm off the side (less the offset)
    a = extent / 2
    gap, _ = body.penetration(np.array([[a, 0.0, 0.0], [0.0, 0.0, 1.0], [a + 1.0, 0.0, -1.0]]))
    assert gap == pytest.approx([0.0, 1.0, 1.0 - H / 2], abs=1e-15)


def test_one_list_for_physics_and_pictures(monkeypatch):
    """contact_bodies and the pictures both take Scene.bodies(): change that list and both follow."""
    sc = scenes.load("square-on-disc")
    assert bodies_of(sc) == sc.bodies()
    fake = [
        {"type": "sphere", "centre": (1.0, 2.0, -3.0), "radius": 2.5, "offset": 0.01, "friction": 0.2},
        {"type": "plane", "point": (0.0, 0.0, -30.0), "normal": (0.0, 0.0, 1.0), "offset": 0.0, "friction": 0.0},
    ]
    monkeypatch.setattr(scenes.Scene, "bodies", lambda self: [dict(b) for b in fake])
    ball, floor = contact_bodies(sc)
    assert isinstance(ball, Sphere) and ball.radius == 2.5 and list(ball.center) == [1.0, 2.0, -3.0]
    assert (ball.offset, ball.friction, floor.point[2]) == (0.01, 0.2, -30.0)
    assert bodies_of(sc) == fake[:1]  # planes are not drawn
    # the pedestal the scene reports for its area and pictures is the one of the list (none here:
    # then the recipe's own, all the same)
    assert sc.pedestal()["diameter"] == 20.0


def test_opt_out_leaves_no_pedestal_body():
    sc = scenes.load("square-on-disc").with_overrides({"geometry.pedestal_contact": False})
    assert sc.bodies() == [] and contact_bodies(sc) == [] and bodies_of(sc) == []
    # the sheet still lies on the recipe's pedestal: its area enters the DC as before
    assert sc.pedestal()["diameter"] == 20.0 and sc.pedestal()["shape"] == "disc"
    # the packaged scenes say so; the key is no mesh parameter (geometry stays the recipe's)
    assert scenes.load("square-on-disc").pedestal_contact is True and sc.pedestal_contact is False
    assert "pedestal_contact" not in sc.geometry


def test_cusick_scene_resolves_from_the_recipe(tmp_path):
    sc = scenes.load(_scene_file(tmp_path, CUSICK))
    support, clamp = sc.bodies()
    # every key the table leaves out comes from the recipe's pedestal (Ø20, top at -h/2, offset h/2)
    assert support == {
        "type": "pedestal",
        "shape": "disc",
        "diameter": 20.0,
        "centre": (0.0, 0.0, -H / 2),
        "height": HEIGHT["square-on-disc"],
        "edge_radius": 0.0,
        "offset": H / 2,
        "friction": 0.0,
        "support": "cusick",
        "role": "support",
        "origin": "contact[0]",
        "disc_thickness": 0.4,
        "stem_diameter": 6.0,
        "clamp_diameter": 16.0,
        "clamp_thickness": 0.5,
    }
    # the clamp lies on the sheet: lower face at +h/2, top 0.5 cm above it, offset h/2
    assert clamp["role"] == "clamp" and clamp["diameter"] == 16.0 and clamp["height"] == 0.5
    assert clamp["centre"] == pytest.approx((0.0, 0.0, H / 2 + 0.5), abs=1e-15)
    assert clamp["offset"] == H / 2 and clamp["origin"] == "contact[0].clamp"
    disc, top = contact_bodies(sc)
    assert isinstance(disc, CusickSupport) and (disc.radius, disc.stem_radius, disc.disc_thickness) == (10.0, 3.0, 0.4)
    assert isinstance(top, Pedestal) and top.radius == 8.0
    assert bodies_of(sc) == [support, clamp]
    # the clamped rim touches both (gap 0 to round-off) and the starting check accepts it: the
    # rim's nodes are fixed; a free node 1 cm out on the flat sheet is h/2 above the disc's edge line
    mesh, _ = build_scene_mesh(sc, "4x32")
    fixed = support_mask(sc, mesh)
    check_initial_contact(sc, mesh, fixed)
    rim = mesh.nodes[fixed[:, :3].all(axis=1)]
    assert np.abs(disc.penetration(rim)[0]).max() < 1e-14
    assert disc.penetration([[11.0, 0.0, 0.0]])[0][0] == pytest.approx(math.hypot(1.0, H / 2) - H / 2, abs=1e-14)
    # the same check refuses a sheet lowered 10 um into the support when nothing holds it
    U0 = np.tile([0.0, 0.0, -1e-3, 0.0, 0.0, 0.0], mesh.n_nodes)
    with pytest.raises(InputError, match=r"contact\[0\] \(pedestal at .*\): 32 node\(s\) .* deepest 0\.001 cm"):
        check_initial_contact(sc, mesh, np.zeros_like(fixed), U0=U0)


def _cusick(centre=(1.0, -2.0, 0.5), R=10.0, t=0.4, r=3.0, height=10.0):
    return CusickSupport(centre, R, t, r, height=height)


def _at(body, rho, dz, phi=0.7):
    """The point at radius rho about the body's axis (angle phi) and dz above its top face."""
    c = body.top_center
    return np.array([c[0] + rho * math.cos(phi), c[1] + rho * math.sin(phi), c[2] + dz])


def test_cusick_distance_against_hand_formulas():
    """The disc (R = 10, t = 0.4) on the stem (r = 3) down to the base 10 cm below the top, off
    the origin.  Tolerance 1e-12 cm: the kernel and the formulas differ by the round-off of sums
    and square roots of O(10) cm numbers (~1e-15 cm); a wrong face or sign is off by >= 0.1 cm."""
    b = _cusick()
    R, t, r = 10.0, 0.4, 3.0
    er = np.array([math.cos(0.7), math.sin(0.7), 0.0])  # the radial direction of _at
    up, down = np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0])
    cases = [
        (5.0, 0.7, 0.7, up),  # above the disc's top face
        (5.0, -t - 1.5, 1.5, down),  # under the overhang: the disc's underside (1.5) nearer than the stem (2)
        (3.5, -t - 2.0, 0.5, er),  # under the overhang: the stem's side (0.5) nearer than the underside (2)
        (r, -5.0, 0.0, er),  # on the stem's side
        (2.0, -0.1, -0.1, up),  # inside the disc above the stem: 0.1 under the top face
        (1.0, -5.0, -2.0, er),  # inside the stem: 2 from its side (4.6 from the disc, 5 from the base)
        (R + 1.0, 1.0, math.sqrt(2.0), (er + up) / math.sqrt(2.0)),  # beyond the disc's top edge
        (R + 1.0, -t - 1.0, math.sqrt(2.0), (er + down) / math.sqrt(2.0)),  # beyond its lower edge
        (r + 1.0, -10.0 - 1.0, math.sqrt(2.0), (er + down) / math.sqrt(2.0)),  # beyond the stem's foot
    ]
    for rho, dz, g_want, n_want in cases:
        g, n = b.signed_distance(_at(b, rho, dz)[None, :])
        assert g[0] == pytest.approx(g_want, abs=1e-12), (rho, dz)
        assert n[0] == pytest.approx(n_want, abs=1e-12), (rho, dz)


def test_cusick_distance_is_exact_outside_and_1_lipschitz():
    rng = np.random.default_rng(7)
    # a stem as wide as the disc makes one cylinder: outside it, the union's distance is the
    # cylinder's (exact distances agree to round-off, 1e-12 cm as above)
    b = _cusick(r=10.0)
    cyl = Pedestal((1.0, -2.0, 0.5), radius=10.0, height=10.0)
    x = np.array([1.0, -2.0, -4.5]) + rng.uniform(-15.0, 15.0, size=(4000, 3)) * [1.0, 1.0, 0.8]
    g_cyl, n_cyl = cyl.signed_distance(x)
    out = g_cyl > 0.0
    assert out.sum() > 1000
    g, n = b.signed_distance(x)
    np.testing.assert_allclose(g[out], g_cyl[out], rtol=0, atol=1e-12)
    np.testing.assert_allclose(n[out], n_cyl[out], rtol=0, atol=1e-12)
    # the narrow-stem body: |g(x) - g(y)| <= |x - y| (the candidates' margin relies on it; 1e-12
    # for round-off), and n = grad g by central differences (step 1e-6: truncation ~1e-12 away
    # from edges, round-off 1e-16/1e-6 = 1e-10; allowed 1e-6) at points off the medial surfaces
    b = _cusick()
    y = x + rng.normal(scale=0.5, size=x.shape)
    gx, nx = b.signed_distance(x)
    gy, _ = b.signed_distance(y)
    assert np.all(np.abs(gx - gy) <= np.linalg.norm(x - y, axis=1) + 1e-12)
    eps = 1e-6
    fd = np.stack(
        [(b.signed_distance(x + eps * e)[0] - b.signed_distance(x - eps * e)[0]) / (2 * eps) for e in np.eye(3)], 1
    )
    smooth = np.linalg.norm(fd, axis=1) > 1.0 - 1e-6  # a kink (medial surface) in the stencil shortens it
    assert smooth.sum() > 3000
    np.testing.assert_allclose(nx[smooth], fd[smooth], rtol=0, atol=1e-6)


def test_pictures_draw_the_bodies_as_they_are(tmp_path):
    """A solid pedestal down to its base; a Cusick support as its disc (radius R, thickness t) on its
    stem (radius r) down to the base; the clamp as a short disc on the sheet."""
    support, clamp = scenes.load(_scene_file(tmp_path, CUSICK)).bodies()
    top = -H / 2
    P = np.concatenate([s.points for s in pedestal_surfaces(support)])
    rho = np.hypot(P[:, 0], P[:, 1])
    assert P[:, 2].max() == pytest.approx(top, abs=1e-12) and P[:, 2].min() == pytest.approx(
        top - HEIGHT["square-on-disc"], abs=1e-12
    )
    assert rho.max() == pytest.approx(10.0, rel=1e-12)
    # below the disc only the stem: nothing drawn wider than r = 3 (polygon corners on the circle)
    assert rho[P[:, 2] < top - 0.4 - 1e-9].max() == pytest.approx(3.0, rel=1e-12)
    C = np.concatenate([s.points for s in pedestal_surfaces(clamp)])
    assert (C[:, 2].min(), C[:, 2].max()) == pytest.approx((H / 2, H / 2 + 0.5), abs=1e-12)
    assert np.hypot(C[:, 0], C[:, 1]).max() == pytest.approx(8.0, rel=1e-12)
    solid = scenes.load("square-pedestal").bodies()[0]
    S = np.concatenate([s.points for s in pedestal_surfaces(solid)])
    assert (S[:, 2].min(), S[:, 2].max()) == pytest.approx((top - HEIGHT["square-pedestal"], top), abs=1e-12)
    assert np.abs(S[:, :2]).max() == pytest.approx(5.0, rel=1e-12)


@pytest.mark.parametrize(
    "extra, key, message",
    [
        (
            CUSICK.replace("stem_diameter = 6.0", "stem_diameter = 21.0"),
            "contact[0].stem_diameter",
            "wider than the disc",
        ),
        ('[[contact]]\ntype = "pedestal"\ndisc_thickness = 0.4\n', "contact[0].disc_thickness", "applies to a Cusick"),
        (
            '[[contact]]\ntype = "pedestal"\nsupport = "cusick"\nstem_diameter = 3.0\n',
            "contact[0].disc_thickness",
            "required",
        ),
        (CUSICK.replace("clamp_thickness = 0.5\n", ""), "contact[0].clamp_thickness", "needs both"),
        (CUSICK.replace("clamp_diameter = 16.0", "clamp_diameter = 24.0"), "contact[0].clamp_diameter", "wider than"),
        (CUSICK.replace("disc_thickness = 0.4", "disc_thickness = 40.0"), "contact[0].disc_thickness", "smaller than"),
        (
            CUSICK.replace('type = "pedestal"', 'type = "pedestal"\nshape = "square"\nsize = 20.0'),
            "contact[0].support",
            "is a disc",
        ),
        ("", "geometry.pedestal_contact", "remove one"),
    ],
)
def test_bad_supports_are_one_line_errors(tmp_path, extra, key, message):
    if key == "geometry.pedestal_contact":  # the opt-out and a pedestal table contradict each other
        p = _scene_file(tmp_path, CUSICK)
        p.write_text(p.read_text().replace("pedestal_contact = true", "pedestal_contact = false"))
    else:
        p = _scene_file(tmp_path, extra)
    with pytest.raises(InputError, match=f"^{p}: " + key.replace("[", r"\[").replace("]", r"\]") + ": .*" + message):
        scenes.load(p)


def test_cli_refuses_a_stem_wider_than_its_disc(tmp_path):
    p = _scene_file(tmp_path, CUSICK.replace("stem_diameter = 6.0", "stem_diameter = 21.0"))
    out = tmp_path / "out"
    env = {**os.environ, "NUMBA_NUM_THREADS": "1"}
    r = subprocess.run(
        [sys.executable, "-m", "solidshell", "run", str(p), "--mesh", "4x32", "--solver", "relax", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
        cwd=tmp_path,
    )
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "contact[0].stem_diameter" in lines[0] and "wider than the disc" in lines[0]
    assert not out.exists() and sorted(x.name for x in Path(tmp_path).iterdir()) == ["mine.toml"]
