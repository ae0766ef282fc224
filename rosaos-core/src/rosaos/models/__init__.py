"""Model selection, and the offline local-intent engine."""
