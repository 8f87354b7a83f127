"""adapt.ramp (coarse-to-fine sequencing of an adaptive relaxation, docs/adaptivity.md): the stages'
caps, their loose steady states, and the refusal in explicit dynamics."""

from __future__ import annotations

import pytest

from solidshell.errors import InputError
from solidshell.run import run_scene
from solidshell.scenes import load
from solidshell.scenes.build import build_scene_mesh

SCENE = "square-pedestal"
OVER = {"adapt.levels": 2, "adapt.ramp": True, "output.pictures": [], "output.snapshots": []}


def test_a_ramp_relaxes_on_level_one_first_then_allows_level_two():
    """Stage 1 may split to level 1 only: until its (loose) steady state the mesh has at most the
    nodes of the all-level-1 mesh 12x4x4; the stage change comes at a steady check (a multiple of
    check_every = 100 steps) and the run goes on past it to level 2."""
    out = run_scene(SCENE, solver="relax", adaptive=True, progress=False, overrides=OVER, max_steps=20000)
    s = out.summary
    assert s["adapt_ramp"] is True
    stages = s["ramp_stages"]
    assert len(stages) == 1 and stages[0]["cap"] == 2
    assert stages[0]["step"] % 100 == 0 and 0 < stages[0]["step"] < s["steps"]
    level1 = build_scene_mesh(load(SCENE), "12x4x4")[0].n_nodes
    before = [n for t, n, _ in s["active_nodes_history"] if t <= stages[0]["t"]]
    assert max(before) <= level1  # nothing finer than level 1 before the stage change
    assert s["max_level_reached"] == 2
    assert s["max_active_nodes"] > max(before)  # the level-2 stage refined further


def test_a_ramp_is_refused_in_explicit_dynamics(tmp_path):
    with pytest.raises(InputError, match="adapt.ramp"):
        run_scene(SCENE, solver="explicit", adaptive=True, progress=False, overrides=OVER, t_end=0.01, out_dir=tmp_path)
