"""The typed events of rosaOS: a low layer every other package may import.

- :mod:`~rosaos.events.types`: the kernel's events and their payloads (user text, device notice,
  error, fired timer) and the ``POST /event`` body;
- :mod:`~rosaos.events.callback`: how a process ended (``WorkerCallback``);
- :mod:`~rosaos.events.plan`: the offline engine's plan, a typed field of a launch, a job and a
  callback.

Nothing here imports another rosaOS package except :mod:`rosaos.receipts`.
"""
