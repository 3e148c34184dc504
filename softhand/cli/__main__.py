"""``python -m softhand.cli``: the ``softhand`` command."""

from softhand.cli.app import run

run()
