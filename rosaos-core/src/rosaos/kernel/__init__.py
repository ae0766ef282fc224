"""The kernel: event store, kernel loop, kernel agent and its tools, HTTP API."""
