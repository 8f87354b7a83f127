"""Fast checks around the static solver's registry entry and the static verification script."""

import numpy as np
import pytest

from solidshell.errors import InputError
from solidshell.solvers import static


class _P:
    """A stand-in Problem: run() must refuse unknown settings before touching the model."""

    model = None
    fixed = np.zeros((1, 6), bool)
    loads = np.zeros((1, 6))
    prescribed = None
    contact = None


def test_unknown_static_setting_is_an_input_error():
    with pytest.raises(InputError, match=r"solver\.static: unknown setting 'cc' \(known: ") as e:
        static.run(_P(), {"method": "paper", "cc": 0.01})
    msg = str(e.value)
    assert "cc" in msg and "known:" in msg and "c," in msg and "max_iter" in msg


def test_case_labels():
    from verification.static_scenes import PAPER_MAX_ITER, parse_label

    assert parse_label("newton") == {"method": "newton"}
    assert parse_label("paper-c0.02") == {"method": "paper", "c": 0.02, "max_iter": PAPER_MAX_ITER}
    assert parse_label("paper-c0.01:maxiter50")["max_iter"] == 50
    assert parse_label("arclength") == {"method": "arclength"}


def test_other_solver_settings_are_not_errors_but_typos_are():
    # keys of the explicit / relax solvers are tolerated (one dict for several solvers) ...
    with pytest.raises(InputError, match=r"solver\.static: unknown setting 'tol_x' \(known: ") as e:
        static.run(_P(), {"method": "newton", "t_end": 1.0, "alpha": 5.0, "tol_x": 1e-3})
    # ... but the typo is named, and only it
    assert "tol_x" in str(e.value) and "t_end" not in str(e.value).split(";")[0]
