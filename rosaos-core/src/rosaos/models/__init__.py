"""Model selection, and the adapters that run the offline engine as pydantic-ai models.

- ``select``: a serializable :class:`~rosaos.models.select.ModelSpec` → a pydantic-ai model;
- ``defaults``: the kernel's and the processes' models from the configuration;
- ``routing``: ``[models] prefer_local``, offline engine first or the LLM;
- the offline engine (:mod:`rosaos.intents`) as pydantic-ai models, so the kernel and workers
  run unchanged:

  - ``kernel_model``: :class:`LocalIntentModel`, the kernel's offline model (sentence → ``launch_process``);
  - ``process_model``: :class:`LocalPlanModel`, a process's offline model (runs the task's plan);
  - ``conversation``: reading pydantic-ai messages (events, tool calls, results) for both.
"""
