"""The relaxation settings the paper-figure scripts hand to the runner, as the solver reads them: the
scenes' [solver.relax] preset ("fast" = FIRE) fills every key a script does not name, and FIRE
ignores alpha, so a script that means the paper's Rayleigh path must name the damping (until
2eacc4d, Figs. 11-13 ran FIRE: Fig. 11's alpha 5 and 1 were one run)."""

from types import SimpleNamespace

import numpy as np
import pytest

from paper_figures import _sphere, common, fig11
from solidshell.scenes import load
from solidshell.solvers.explicit.settings import parse_settings


class _Stop(Exception):
    pass


def _record(monkeypatch, stop_after):
    calls = []

    def fake_run(scene, mesh=None, solver=None, overrides=None, adaptive=None, **settings):
        calls.append((scene, solver, settings))
        if len(calls) >= stop_after:
            raise _Stop(f"stopped after {stop_after} run(s)")
        out = SimpleNamespace(mesh=SimpleNamespace(nodes=np.zeros((1, 3))), U=np.zeros((1, 6)))
        return out, {"converged": True, "fold_count": 8, "drape_coefficient": 0.06}

    monkeypatch.setattr(common, "run", fake_run)
    return calls


def _effective(scene, settings):
    s = load(scene).solver_settings("relax")
    s.update(settings)
    return parse_settings(s, True)


def test_fig11_runs_rayleigh_alpha_50_and_10(monkeypatch, tmp_path):
    calls = _record(monkeypatch, stop_after=2)
    with pytest.raises(_Stop, match=r"stopped after 2 run\(s\)"):
        fig11.make(tmp_path, quick=False)
    got = [_effective(sc, kw) for sc, solver, kw in calls]
    assert [(g.damping, g.alpha, g.mass_scaling, g.mass_scaling_mode) for g in got] == [
        ("rayleigh", 50.0, 100.0, "director"),
        ("rayleigh", 10.0, 100.0, "director"),
    ]


@pytest.mark.parametrize("quick, damping", [(False, "rayleigh"), (True, "kinetic")])
def test_sphere_figures_name_their_damping(monkeypatch, quick, damping):
    calls = _record(monkeypatch, stop_after=1)
    with pytest.raises(_Stop, match=r"stopped after 1 run\(s\)"):
        _sphere.run_sphere("60x60", quick)
    ((sc, solver, kw),) = calls
    s = _effective(sc, kw)
    assert solver == "relax" and s.damping == damping
    if not quick:  # the paper's alpha 5 with all masses x100, as alpha 50 with the director masses x100
        assert (s.alpha, s.mass_scaling, s.mass_scaling_mode) == (50.0, 100.0, "director")
