"""Build hook: ship the repository's copier template (../templates/driver) inside rosaos.

The template lives at the repo root where driver authors look for it. In a build from the repo,
this hook adds it to the wheel as ``rosaos/_templates/driver`` and to the sdist as
``src/rosaos/_templates/driver``; a wheel built from that sdist then finds it already in place.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface


class TemplateHook(BuildHookInterface):  # type: ignore[type-arg]
    PLUGIN_NAME = "custom"

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        template = Path(self.root).parent / "templates" / "driver"
        if version == "editable" or not template.is_dir():
            # Editable installs read the repo's template directly (see rosaos.scaffold); an sdist
            # build finds the template already under src/rosaos/_templates.
            return
        target = "rosaos/_templates/driver" if self.target_name == "wheel" else "src/rosaos/_templates/driver"
        build_data.setdefault("force_include", {})[str(template)] = target
