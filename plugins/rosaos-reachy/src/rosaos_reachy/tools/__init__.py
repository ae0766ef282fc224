"""The Reachy Mini's MCP tools by role; each module has ``register(mcp, backend)``."""
