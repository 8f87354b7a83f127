"""The suite runs in a random order (pytest-randomly, pyproject's [test] extra).  pytest-randomly names
its seed in the session header, which ``-q`` (the README's command) leaves out: the summary names it
too, so that a failure that depends on the order can be repeated with ``--randomly-seed=N``."""


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    seed = getattr(config.option, "randomly_seed", None)
    if isinstance(seed, int):
        terminalreporter.write_line(f"random test order: repeat it with --randomly-seed={seed}")
