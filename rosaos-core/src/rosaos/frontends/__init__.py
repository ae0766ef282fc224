"""Front ends: the web page, the CLI chat and the voice pipeline."""
