"""``rosaos bench``: the task-success benchmark, run through the full system on simulators.

- :mod:`rosaos.bench.tasks`: the task file format (``../shared/bench/README.md``) and loading it;
- :mod:`rosaos.bench.expect`: the checking rules;
- :mod:`rosaos.bench.sim_world`: a task file's world, served in-process and restarted per task;
- :mod:`rosaos.bench.runner`: one kernel per file, each task posted as ``[User said]``, settled, checked;
- :mod:`rosaos.bench.results` and :mod:`rosaos.bench.report`: the numbers, the table, the JSON;
- :mod:`rosaos.cli.bench_command`: the ``rosaos bench`` command itself.
"""
