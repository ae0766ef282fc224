"""The offline local-intent engine: sentences → processes with exact plans, no model, no network.

Three layers, each importing only the ones above it in this list (the plan format every layer
shares is :mod:`rosaos.events.plan`, in the low layer):

- :mod:`~rosaos.intents.grammar`: what can be said. Drivers' ``intents.yaml`` files, Home
  Assistant's built-in templates and how a driver maps them, each device's vocabulary (names,
  areas), the engine's replies per language, and the shape of a timer request.
- :mod:`~rosaos.intents.understanding`: what a sentence means in this world. hassil matching
  (:class:`~rosaos.intents.understanding.matching.IntentMatcher`), readings ranked per clause,
  rephrasings, the fuzzy model, refusals → a
  :class:`~rosaos.intents.understanding.match_result.MatchResult`.
- :mod:`~rosaos.intents.planning`: what to do about it. Follow-ups ("X, then Y"), the answer to
  a device notice, timer turns.

The engine reaches the kernel and the workers as pydantic-ai models, through the adapters in
:mod:`rosaos.models` (``kernel_model``, ``process_model``); nothing here runs an agent.
"""
