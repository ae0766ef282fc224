"""rosaOS driver for Spotify playback.

- ``plugin.py``: the ``DriverSpec`` rosaOS loads, and the backend factories.
- ``settings.py``: the settings of one instance (client id, redirect URI, device, market).
- ``server.py``: the MCP tools a process agent calls (``play``, ``pause``, ``set_volume``, ...).
- ``backend.py``: what both backends do, and the state and report shapes they answer in.
- ``web_api.py``: the ``real`` backend, the Spotify Web API through spotipy;
  ``errors.py`` turns Spotify's failures into fix-it messages.
- ``auth.py``, ``login.py``: OAuth with PKCE, the token file, ``rosaos devices login``.
- ``simulator.py``: the ``sim`` backend, a player over ``catalog.py``'s tracks.
- ``prompt.md``, ``intents.yaml``: the device prompt and the offline sentence templates.
"""
