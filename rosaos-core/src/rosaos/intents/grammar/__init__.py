"""What can be said: templates, Home Assistant intents, device vocabulary, replies, timer phrases.

- ``intents_file``: a driver's ``intents.yaml`` (hassil templates + the tool each intent calls);
- ``ha_mapping``, ``ha_intents``: a driver's ``homeassistant:`` table; HA's built-in templates;
- ``vocabulary``: what the engine knows of each device (spoken names, areas, its intents file);
- ``phrases``: the engine's replies and word lists, per language;
- ``timer_phrases``: a sentence → set, list or cancel a timer.
"""
