"""Cross-package tests. This folder goes on sys.path so tests (and workers, via PYTHONPATH) can
import the scripted models in kernel_scripts.py."""

import sys
from pathlib import Path

HERE = str(Path(__file__).parent)
if HERE not in sys.path:
    sys.path.insert(0, HERE)
