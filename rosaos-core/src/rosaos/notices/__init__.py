"""Device notices, in one package: what a device reports on its own, from the driver to the reply.

Each module sits at the layer of what it serves (import-linter holds the layers module by module,
so this package is no layer of its own, like :mod:`rosaos.memory`):

- :mod:`~rosaos.notices.notice_board`: the driver side, ``NoticeSpec``, the per-device ``NoticeBoard``,
  ``GET /notices`` (re-exported by :mod:`rosaos.drivers`);
- :mod:`~rosaos.notices.notice_watcher`: the kernel side, long-polls every device and enqueues
  ``device_notice`` events;
- :mod:`~rosaos.notices.notice_plan`: how the offline engine answers a notice;
- :mod:`~rosaos.notices.notice_text`: how a ``[Device notice]`` reads to an LLM kernel.

Nothing is imported here: a driver importing the board must not load the kernel's watcher.
"""
