"""What can be said: templates, Home Assistant intents, device vocabulary, replies.

- ``intents_file``: a driver's ``intents.yaml`` (hassil templates + the tool each intent calls);
- ``ha_mapping``, ``ha_intents``: a driver's ``homeassistant:`` table; HA's built-in templates;
- ``vocabulary``: what the engine knows of each device (spoken names, areas, its intents file);
- ``phrases``: the engine's replies and word lists, per language.

Timer sentences are :mod:`rosaos.timers.timer_phrases`.
"""
