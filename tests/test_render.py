"""Pictures: depth order (a sheet above a body hides it, whatever the renderer), the warp-label
rule, and a run picture written as a sane PNG."""

import numpy as np
import pytest

from solidshell.mesh import ShellMesh
from solidshell.render import ViewStyle, axis_labels, draw_view, height_norm, renderer, scene_warp_deg, vtk_backend


def _sheet(n=8, size=10.0, z=0.0):
    s = np.linspace(-size / 2, size / 2, n + 1)
    Xg, Yg = np.meshgrid(s, s)
    nodes = np.column_stack([Xg.ravel(), Yg.ravel(), np.full(Xg.size, z)])
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    a = (i * (n + 1) + j).ravel()
    quads = np.column_stack([a, a + 1, a + n + 2, a + n + 1])
    return ShellMesh(nodes, quads=quads)


# a box (pedestal) under the sheet's centre, its top 1 cm below the sheet; a sphere touching it.
# A pedestal is drawn down to its base: 2.4 cm high keeps the sheet in the middle of the iso
# picture (a 10 cm column would pull the picture's centre pixel off the sheet, onto the column)
BOX = {"type": "pedestal", "shape": "square", "size": 4.0, "centre": (0.0, 0.0, -1.0), "height": 2.4}
BALL = {"type": "sphere", "centre": (0.0, 0.0, -3.05), "radius": 3.0}


def _centre_pixel(backend, monkeypatch, tmp_path, view, body):
    """RGB in [0,1] at the centre of a picture of the flat sheet above ``body``."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.image as mimg
    import matplotlib.pyplot as plt

    monkeypatch.setenv("SOLIDSHELL_RENDERER", backend)
    mesh = _sheet(7)  # odd: the centre pixel is inside an element, not on a mesh line
    fig = plt.figure(figsize=(3, 3))
    ax = fig.add_axes([0, 0, 1, 1])
    # the sheet sits at the top of the colour scale: yellow in viridis, far from the body's grey
    draw_view(
        ax,
        mesh,
        mesh.nodes,
        view,
        bodies=[body],
        norm=height_norm(mesh.nodes - [0, 0, 1], mesh.nodes),
        style=ViewStyle(labels=False, height_px=200),
    )
    ax.set_axis_off()
    p = tmp_path / f"{backend}-{view}.png"
    fig.savefig(p, dpi=80)
    plt.close(fig)
    img = mimg.imread(p)
    h, w = img.shape[:2]
    return img[h // 2, w // 2, :3]


def _backends():
    out = ["matplotlib"]
    if vtk_backend.available()[0]:
        out.append("vtk")
    return out


@pytest.mark.parametrize("backend", _backends())
@pytest.mark.parametrize("view", ["top", "iso"])
@pytest.mark.parametrize("body", [BOX, BALL], ids=["box", "sphere"])
def test_sheet_above_body_hides_it(backend, view, body, monkeypatch, tmp_path):
    # The body is grey (R = G = B); the sheet is viridis' yellow (blue far below red and green),
    # dimmed by its shading.  The old painter drew the body over the sheet (grey at the centre).
    r, g, b = _centre_pixel(backend, monkeypatch, tmp_path, view, body)
    assert b < 0.5 * g and r > 0.3, f"centre pixel {r:.2f},{g:.2f},{b:.2f} is not the sheet's yellow"


def test_warp_labels_follow_the_warp_angle():
    assert axis_labels(0.0)["x"].endswith("(warp)") and axis_labels(0.0)["y"].endswith("(weft)")
    assert axis_labels(180.0)["x"].endswith("(warp)")
    assert axis_labels(90.0)["x"].endswith("(weft)") and axis_labels(90.0)["y"].endswith("(warp)")
    assert axis_labels(-90.0)["x"].endswith("(weft)")
    lab = axis_labels(30.0)
    assert "warp" not in lab["x"] and "weft" not in lab["y"] and "30" in lab["note"]
    assert axis_labels(None) == {"x": "x [cm]", "y": "y [cm]", "z": "z [cm]", "note": ""}


def test_scene_warp_angle_reaches_the_labels():
    from solidshell.scenes import load

    assert scene_warp_deg(load("strip-weft")) == pytest.approx(90.0)
    assert axis_labels(scene_warp_deg(load("strip-weft")))["x"] == "x [cm]  (weft)"
    assert scene_warp_deg(None) is None


def test_run_picture_is_a_sane_png(tmp_path):
    import matplotlib.image as mimg

    from solidshell.plotting import render
    from solidshell.scenes import load

    mesh = _sheet(4, 20.0)
    p = render(tmp_path / "iso.png", mesh, None, view="iso", title="t", scene=load("square-pedestal"))
    img = mimg.imread(p)
    assert 300 < img.shape[0] < 2000 and 300 < img.shape[1] < 2000  # ~7x6 in at 130 dpi
    assert p.stat().st_size > 10_000  # not a blank image
    assert renderer() in ("vtk", "matplotlib")


def _tight_figure(view: str, title: str = "a title\nand a subtitle"):
    """A picture's figure: its image (random pixels standing in for VTK's), title, axis labels
    and the colour bar beside it."""
    from solidshell import plotting

    mesh = _sheet(4, 20.0)
    X = mesh.nodes + np.column_stack([0 * mesh.nodes[:, :2], -0.01 * mesh.nodes[:, 0] ** 2])
    fig = plotting._figure((7.0, 6.0))
    ax = fig.add_subplot(111)
    sm = draw_view(ax, mesh, X, view, norm=height_norm(X), warp_deg=0.0)
    ax.imshow(np.random.default_rng(0).random((90, 160, 3)), extent=ax.get_xlim() + ax.get_ylim(), zorder=0)
    plotting.colorbar(fig, ax, sm)
    ax.set_title(title, fontsize=9.5)
    return fig


def _aligned_difference(a, b, shifts=(0, 1)) -> float:
    """The smallest mean |a - b| over the offsets ``shifts`` (px) of either picture in x and y."""
    h, w = min(a.shape[0], b.shape[0]) - max(shifts), min(a.shape[1], b.shape[1]) - max(shifts)
    return min(
        float(np.abs(a[dy : dy + h, dx : dx + w] - b[ey : ey + h, ex : ex + w]).mean())
        for dy in shifts
        for dx in shifts
        for ey in shifts
        for ex in shifts
    )


@pytest.mark.parametrize("view", ["top", "side", "iso"])
def test_picture_is_savefigs_tight_one(tmp_path, monkeypatch, view):
    """plotting._save_tight_png draws the figure once and cuts it to the padded box of its artists:
    the picture is savefig(bbox_inches="tight")'s of the same figure, the same size, up to the
    sub-pixel offset of the box (savefig shifts the drawing by it, the cut snaps to whole pixels).
    Tolerance: mean |difference| <= 0.02 of full scale at the best 0/1 px alignment; measured
    0.006-0.010 (antialiased text and the resampled random image moved by < 1 px); a cut 3 px off
    gives more (asserted, so the comparison can fail)."""
    import matplotlib.image as mimg

    from solidshell import plotting

    monkeypatch.setenv("SOLIDSHELL_RENDERER", "matplotlib")
    ours, ref = tmp_path / "ours.png", tmp_path / "ref.png"
    fig = _tight_figure(view)
    plotting._save_tight_png(fig, ours, 130, pad_inches=0.15)
    _tight_figure(view).savefig(ref, dpi=130, format="png", bbox_inches="tight", pad_inches=0.15)
    a, b = (mimg.imread(p)[..., :3] for p in (ours, ref))
    assert a.shape == b.shape and a.shape[1] > 500  # the whole 7 in wide figure, not a crop of it
    assert _aligned_difference(a, b) <= 0.02
    assert _aligned_difference(a[3:], b[:-3]) > 0.02  # 3 px off: the comparison tells
    assert fig.dpi == _tight_figure(view).dpi and all(im.get_visible() for im in fig.axes[0].get_images())


def test_picture_wider_than_its_figure_is_savefigs(tmp_path, monkeypatch):
    """A title wider than the figure puts the tight box outside the figure's pixels: then the
    picture is savefig's own, byte for byte (its canvas widened to the box)."""
    from solidshell import plotting

    monkeypatch.setenv("SOLIDSHELL_RENDERER", "matplotlib")
    wide = "a title much wider than the seven inches of its figure " * 3
    ours, ref = tmp_path / "ours.png", tmp_path / "ref.png"
    plotting._save_tight_png(_tight_figure("top", wide), ours, 130, pad_inches=0.15)
    _tight_figure("top", wide).savefig(ref, dpi=130, format="png", bbox_inches="tight", pad_inches=0.15)
    assert ours.read_bytes() == ref.read_bytes()


def test_figures_cli_refuses_an_unknown_figure(capsys):
    from solidshell.cli import main

    assert main(["figures", "4", "3"]) == 2  # checked before any figure runs
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown figure '3'" in err[0] and "4, 5, 6" in err[0] and "22" in err[0]


def test_fig04_quick_renders_over_the_elastica(tmp_path):
    # Fig. 4 in quick mode (four static strips, seconds): the PNG exists with a sane size, and its
    # json carries each strip's tip error against the elastica; the 10x1/20x1 tips are within 0.5 %
    # / 0.2 % of the 5 cm length (verification/strip.py measures 0.45 % and 0.12 %).
    import json

    import matplotlib.image as mimg

    from paper_figures.registry import make_figures

    make_figures(["fig4"], quick=True, out_dir=tmp_path, say=lambda *_: None)
    img = mimg.imread(tmp_path / "fig04.png")
    assert 500 < img.shape[1] < 3000 and 300 < img.shape[0] < 2000
    info = json.loads((tmp_path / "fig04.json").read_text())
    errs = {(r["scene"], r["mesh"]): abs(r["tip_z_error_vs_elastica"]) for r in info["runs"]}
    assert len(errs) == 4
    for (scene, mesh), e in errs.items():
        assert e < (0.025 if mesh == "10x1" else 0.01), (scene, mesh, e)


def test_a_started_probe_gives_available_its_answer(monkeypatch):
    # start_probe launches the same child-process probe early; available() then waits for that
    # child instead of launching another, and gives the answer a fresh probe gives
    fresh = vtk_backend.available()
    monkeypatch.setattr(vtk_backend, "_STATE", {})
    launched = []
    real = vtk_backend._launch
    monkeypatch.setattr(vtk_backend, "_launch", lambda win: launched.append(win) or real(win))
    vtk_backend.start_probe()
    assert len(launched) == 1 and "pending" in vtk_backend._STATE
    assert vtk_backend.available() == fresh
    # a working first window class needs no second launch; a failing one is followed by the next
    assert len(launched) == (1 if fresh[0] else len(vtk_backend._windows()))
    assert "pending" not in vtk_backend._STATE
    vtk_backend.start_probe()  # the answer is known: nothing more is launched
    assert len(launched) == (1 if fresh[0] else len(vtk_backend._windows()))


def test_no_probe_when_matplotlib_is_asked_for(monkeypatch):
    monkeypatch.setattr(vtk_backend, "_STATE", {})
    monkeypatch.setenv("SOLIDSHELL_RENDERER", "matplotlib")
    monkeypatch.setattr(vtk_backend, "_launch", lambda win: pytest.fail("probe launched"))
    vtk_backend.start_probe()
    assert vtk_backend._STATE == {}
