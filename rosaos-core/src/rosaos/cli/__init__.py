"""``rosaos ...``: the command line, the top layer. Nothing below it (kernel, devices, processes,
models, intents) imports it; ``tests/test_layers.py`` checks.

- ``root``: the typer app; declares every command's options and calls its command function,
  importing it lazily so ``rosaos --help`` stays fast;
- ``options``: the options several commands share; ``devices_app``: ``rosaos devices ...``;
- ``up_command``: ``rosaos up``; ``process_commands``: ``ps``, ``kill``, ``estop``;
  ``log_command``: ``log``; ``open_command``: ``open`` (``ps --timers``, ``kill --timer``:
  :mod:`rosaos.timers.timer_commands`);
- ``device_commands``: what ``devices list``, ``devices check`` and ``serve-device`` do;
- ``bench_command``: ``bench``;
- ``console``: the rich console every command prints through.

``rosaos chat`` and ``rosaos voice`` are front ends (:mod:`rosaos.frontends`); ``rosaos
new-driver`` is :mod:`rosaos.scaffold`.
"""

from rosaos.cli.root import app, main

__all__ = ["app", "main"]
