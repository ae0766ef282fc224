"""The kernel's HTTP layer: the FastAPI app, its routes and bodies, and the client that calls it.

- ``app``: :func:`create_app`, the rules around every route (bearer token, origin guard, errors);
- ``routes``: events, updates, processes, devices, emergency stop, the web page;
  ``confirmation_routes``, ``frame_routes``, ``timer_routes``: the rest, by feature;
- ``schemas``: what the routes take and answer, and :class:`KernelRuntime`, what they need
  from the kernel;
- ``login_codes``: one-time login codes that let a browser get the token;
- ``kernel_client``: :class:`KernelClient`, the HTTP client the CLI, front ends and benchmarks use.
"""
