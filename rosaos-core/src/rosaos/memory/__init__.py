"""Memory: named places in their frame, and what people told rosaOS, kept in the data directory.

- :mod:`~rosaos.memory.store`: the SQLite file and its two tables (places, notes);
- :mod:`~rosaos.memory.robots`: reading a robot's pose and frame, and the task that drives it to a place;
- :mod:`~rosaos.memory.memory_tools`: the kernel's memory tools (the offline engine and an LLM use them alike);
- :mod:`~rosaos.memory.memory_phrases` and :mod:`~rosaos.models.memory_turn`: the offline engine's sentences about memory.
"""
