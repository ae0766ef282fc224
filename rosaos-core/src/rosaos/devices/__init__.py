"""Hosting device instances: serve, supervise, health-check, and reach remote ones."""
