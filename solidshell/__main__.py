"""``python -m solidshell ...`` -- the same as the ``solidshell`` command (cli.console: main()'s exit
status, without the interpreter's slow teardown)."""

from .cli import console

console()
