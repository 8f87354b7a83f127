"""The fields written with a run's states (solidshell/run/state_fields.py): each distinct state's
fields computed once, the final state's included although the series writes it last."""

from types import SimpleNamespace

import numpy as np

from solidshell.run import state_fields


def test_final_state_fields_are_computed_once(monkeypatch):
    calls = []

    def of_problem(problem, U, fixed, lam):
        calls.append(lam)
        return ("fields", lam, float(np.sum(U)))

    monkeypatch.setattr(state_fields, "of_problem", of_problem)
    mesh = SimpleNamespace(n_nodes=4)
    solved = SimpleNamespace(problem=SimpleNamespace(model=SimpleNamespace(blocks=())), mesh=mesh, fixed=None)
    fields_of = state_fields.series_fields(None, "static", solved)
    U = np.arange(24.0).reshape(4, 6)
    final = fields_of(1.0, mesh, U)  # result.xdmf
    assert fields_of(1.0, mesh, U.copy()) is final  # result.vtu, deformed.vtu
    # the series from rest: its earlier frames, then the final state again
    first = fields_of(0.0, mesh, 0 * U)
    half = fields_of(0.5, mesh, 0.5 * U)
    assert fields_of(1.0, mesh, U.copy()) is final
    assert calls == [1.0, 0.0, 0.5]
    assert first == ("fields", 0.0, 0.0) and half == ("fields", 0.5, 0.5 * U.sum())
    # another state (or load factor) is computed, not taken from the kept ones
    assert fields_of(1.0, mesh, U + 1.0) == ("fields", 1.0, float(np.sum(U + 1.0)))
    assert fields_of(0.9, mesh, U) == ("fields", 0.9, float(np.sum(U)))
    assert calls == [1.0, 0.0, 0.5, 1.0, 0.9]
