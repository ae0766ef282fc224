"""Model selection, and the offline local-intent engine.

- ``select``: a serializable :class:`~rosaos.models.select.ModelSpec` → a pydantic-ai model.
- The local-intent engine, as pydantic-ai models so the kernel and workers run unchanged:

  - ``kernel_model``: :class:`LocalIntentModel`, the kernel's offline model (sentence → ``launch_process``);
  - ``process_model``: :class:`LocalPlanModel`, a process's offline model (runs the task's plan);
  - ``routing``: ``[models] prefer_local``, local first or LLM;
  - ``matching`` and ``readings``: sentence → processes, with hassil; ``sources``: device names and areas;
  - ``intents_file``, ``ha_mapping``, ``ha_intents``: driver templates, and Home Assistant's;
  - ``plan``: the ``rosaos-plan`` block a task carries; ``phrases``: the replies, per language;
  - ``conversation``: reading pydantic-ai messages (events, tool calls, results).
"""
