"""A module that starts a thread when imported: the fork server must refuse to fork after it."""

from __future__ import annotations

import threading

STOP = threading.Event()
threading.Thread(target=STOP.wait, name="started-at-import", daemon=True).start()
