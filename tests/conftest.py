"""The suite runs in a random order (pytest-randomly, pyproject's [test] extra).  pytest-randomly names
its seed in the session header, which ``-q`` (the README's command) leaves out: the summary names it
too, so that a failure that depends on the order can be repeated with ``--randomly-seed=N``.

The property tests (hypothesis) are derandomized and keep no example database: each draws the
same examples on every run and nothing one run found is replayed by the next, so the suite's
verdict depends neither on the seed nor on what ran before (the database had replayed a case one
run found into the next run of the same checkout).  ``--hypothesis-profile=explore`` draws new
examples each run, with the database, for a search beyond the fixed ones."""

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
    """Raised by the ``after_contact_update`` callback."""


@pytest.fixture
def after_contact_update():
    """(progress callback, its exception): the callback raises the exception two progress reports
    after the first contact update (>= 2 x progress_every steps: a checkpoint written after it)."""
    seen = []

    def stop(frac, text):
        if "contact update" in text or seen:
            seen.append(text)
        if len(seen) >= 3:
            raise StopRun("stopped after a contact update")

    return stop, StopRun
