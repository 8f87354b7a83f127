"""Stored reference data for ``solidshell verify`` and the scripts that make them (README.md).

A package so that the wheel ships the data (``*.json``, ``*.md``) and the checks find them through
``importlib.resources`` (``verification.checks.references``).  Nothing here imports solidshell;
the scripts run on their own (``python -m reference.elastica``, ``python -m reference.kirchhoff_plate``).
"""
