"""The run pipeline (solidshell.run_scene): check -> build -> solve -> summarise -> write.

Modules: ``driver`` (run_scene, RunOutput, the five steps in order and the solve step),
``summary`` (summary.json: what ran, the state's measures, warnings), ``outputs`` (the run folder
and its files), ``progress`` (the progress callback and bar), ``adaptive`` (the §5.5 driver for a
run).  The scene -> problem step is solidshell.scenes.build.
"""

from .driver import RunOutput, run_scene

__all__ = ["RunOutput", "run_scene"]
