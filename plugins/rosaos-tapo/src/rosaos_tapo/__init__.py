"""rosaOS driver for TP-Link Tapo smart bulbs.

- ``plugin.py``: the ``DriverSpec`` rosaOS loads, the settings, and the backend factories.
- ``server.py``: the MCP tools a process agent calls (``turn_on``, ``set_brightness``, ...).
- ``backend.py``: the bulb behind python-kasa, with kasa errors turned into fix-it messages.
- ``simulator.py``: an in-process Tapo L530E that kasa talks to like a real bulb.
- ``colors.py``: the named colours of ``set_color_name``.
- ``prompt.md``, ``intents.yaml``: the device prompt and the offline sentence templates.

Licensed GPL-3.0-or-later because it imports python-kasa (GPL-3.0).
"""
