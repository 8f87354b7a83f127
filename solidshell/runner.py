"""The public face of a run, kept for users' scripts: ``solidshell.runner.run_scene`` /
``build_problem`` / ``RunOutput``.  The pipeline lives in solidshell.run (driver, summary,
outputs, progress, adaptive) and the scene -> problem step in solidshell.scenes.build."""

from .run.driver import RunOutput, run_scene
from .scenes.build import build_problem

__all__ = ["RunOutput", "build_problem", "run_scene"]
