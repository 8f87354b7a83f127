"""Optional extras (issue 40 item 6): without MKL the static solvers fall back to CHOLMOD and say
so in one log line, once per process."""

from __future__ import annotations

import logging
import platform

import pytest

from solidshell.solvers import linear, pardiso


@pytest.mark.skipif(platform.machine().lower() not in ("x86_64", "amd64"), reason="the mkl wheel is x86-64 only")
def test_auto_without_mkl_takes_cholmod_with_one_hint_line(monkeypatch, caplog):
    monkeypatch.setattr(pardiso, "available", lambda: False)
    monkeypatch.setattr(linear, "_HINTED", [])
    with caplog.at_level(logging.WARNING, logger="solidshell"):
        picks = [linear.resolve_factorization("auto", 10**5) for _ in range(3)]
        small = linear.resolve_factorization("auto", 10)  # a small system never asks for MKL
    assert picks == ["cholmod"] * 3 and small == "cholmod"
    lines = [r.getMessage() for r in caplog.records]
    assert len(lines) == 1 and "solidshell[mkl]" in lines[0] and "\n" not in lines[0]
