"""The suite runs in a random order (pytest-randomly, pyproject's [test] extra).  pytest-randomly names
its seed in the session header, which ``-q`` (the README's command) leaves out: the summary names it
too, so that a failure that depends on the order can be repeated with ``--randomly-seed=N``.

The property tests (hypothesis) are derandomized and keep no example database: each draws the
same examples on every run and nothing one run found is replayed by the next, so the suite's
verdict depends neither on the seed nor on what ran before (the database had replayed a case one
run found into the next run of the same checkout).  ``--hypothesis-profile=explore`` draws new
examples each run, with the database, for a search beyond the fixed ones."""

import numpy as np
import pytest
from hypothesis import settings

settings.register_profile("default", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile("default")


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    seed = getattr(config.option, "randomly_seed", None)
    if isinstance(seed, int):
        terminalreporter.write_line(f"random test order: repeat it with --randomly-seed={seed}")


class StopRun(Exception):
    """Raised by the progress callback of ``restart_after_contact_update``."""


@pytest.fixture
def restart_after_contact_update():
    """check(prob, settings, ck, between=None): relax ``prob`` whole; relax it again with checkpoints
    to the path ``ck``, stopped two progress reports after its first contact update (>= 2 x
    progress_every steps: a checkpoint written after it); call ``between(ck)``; restart from ``ck``;
    assert the restart ends on exactly the state and books of the whole run."""
    from solidshell.solvers import explicit

    def check(prob, s, ck, between=None):
        full = explicit.run_relax(prob, s)
        assert full.converged and full.info["contact_augment_updates"] >= 1
        cks = dict(checkpoint=ck, checkpoint_every=37, progress_every=50)
        seen = []

        def stop(frac, text):
            if "contact update" in text or seen:
                seen.append(text)
            if len(seen) >= 3:
                raise StopRun("stopped after a contact update")

        with pytest.raises(StopRun):
            explicit.run_relax(prob, {**s, **cks}, progress=stop)
        if between is not None:
            between(ck)
        again = explicit.run_relax(prob, {**s, **cks, "restart": ck})
        assert again.info["restarted_from_step"] > 0
        assert np.array_equal(again.U, full.U) and again.message == full.message
        for k in ("steps", "energy_balance_error", "contact_augment_updates", "contact_augment_energy_jump"):
            assert again.info[k] == full.info[k], k

    return check
