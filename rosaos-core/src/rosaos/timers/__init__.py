"""Timers, in one package: "turn off the light in ten minutes", from the sentence to the firing.

Each module sits at the layer of what it serves (import-linter holds the layers module by module,
so this package is no layer of its own, like :mod:`rosaos.memory`):

- :mod:`~rosaos.timers.timer_phrases`: a sentence → set, list or cancel a timer (the engine's grammar);
- :mod:`~rosaos.timers.timer_turn`: the offline kernel model's timer turns, and a fired timer carried out;
- :mod:`~rosaos.timers.timer_book`: :class:`~rosaos.timers.timer_book.TimerBook`, durable timers in the event store;
- :mod:`~rosaos.timers.timer_text`: clock times, "in 10 minutes", and the ``[Timer fired]`` text an LLM reads;
- :mod:`~rosaos.timers.timer_tools`: the kernel agent's ``set_timer``, ``list_timers``, ``cancel_timer``;
- :mod:`~rosaos.timers.timer_routes`: ``GET /timers``, ``DELETE /timers/{id}``;
- :mod:`~rosaos.timers.timer_commands`: ``rosaos ps --timers``, ``rosaos kill --timer``.

Nothing is imported here, so importing one module does not drag in the others' layers.
"""
