"""rosaOS: an agentic operating system for embodied LLMs."""

from rosaos.hookspecs import hookimpl

__all__ = ["__version__", "hookimpl"]
__version__ = "0.1.0"
