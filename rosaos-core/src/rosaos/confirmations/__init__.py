"""Confirmations, in one package: a process pauses before a risky call until a person says yes.

Each module sits at the layer of what it serves (import-linter holds the layers module by module,
so this package is no layer of its own, like :mod:`rosaos.memory`):

- :mod:`~rosaos.confirmations.confirming`: the worker's side, the rule and the toolset that asks;
- :mod:`~rosaos.confirmations.confirmation_desk`: the kernel's desk of pending questions;
- :mod:`~rosaos.confirmations.confirmation_chat`: asking people and reading their spoken or typed answer;
- :mod:`~rosaos.confirmations.confirmation_routes`: ``GET/POST /confirmations``, ``GET/POST /confirmations/{id}``.

Nothing is imported here: a worker importing the toolset must not load the kernel's desk.
"""
