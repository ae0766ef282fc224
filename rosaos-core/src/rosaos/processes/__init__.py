"""Processes: the worker pool, worker main, device leases and process prompts."""
