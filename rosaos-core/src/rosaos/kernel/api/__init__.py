"""The kernel's HTTP layer: the FastAPI app, its routes and bodies, and the client that calls it.

- ``app``: :func:`create_app`, the rules around every route (bearer token, origin guard, errors);
- ``routes``: events, updates, processes, devices, emergency stop, the web page;
  ``control_routes``, ``frame_routes``, ``memory_routes``: the rest, by feature (the timer and
  confirmation routes live with their features, in :mod:`rosaos.timers` and
  :mod:`rosaos.confirmations`);
- ``schemas``: what the routes take and answer, and :class:`KernelRuntime`, what they need
  from the kernel;
- ``login_codes``: one-time login codes that let a browser get the token;
- ``kernel_client``: :class:`KernelClient`, the HTTP client the CLI, front ends and benchmarks use.
"""
