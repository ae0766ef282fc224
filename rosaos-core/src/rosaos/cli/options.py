"""The options several commands share: ``--config``, ``--json``, ``--url``, the model options."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

ConfigOption = Annotated[
    Path | None,
    typer.Option(
        "--config",
        "-c",
        help="rosaos.toml to use (default: $ROSAOS_CONFIG, ./rosaos.toml, then the user config dir).",
        exists=False,
        dir_okay=False,
    ),
]
JsonOption = Annotated[bool, typer.Option("--json", help="Print machine-readable JSON.")]
AnswerTimeoutOption = Annotated[
    float,
    typer.Option("--timeout", metavar="SECONDS", min=0.1, help="Seconds get_state may take to answer."),
]
StartTimeoutOption = Annotated[
    float,
    typer.Option(
        "--start-timeout",
        metavar="SECONDS",
        min=0.1,
        help="Seconds a device may take to start: one started here for the check, "
        "or one that `rosaos up` is still starting.",
    ),
]


ModelOption = Annotated[
    str | None,
    typer.Option(
        "--model",
        "-m",
        help="Kernel model: any pydantic-ai model string (openai:gpt-5.2, anthropic:…, google:…, groq:…) "
        "or 'openai-compatible' with --base-url and --model-name.",
    ),
]
ProcessModelOption = Annotated[
    str | None, typer.Option(help="Model for process agents (default: the kernel's).")
]
BaseUrlOption = Annotated[
    str | None, typer.Option(help="OpenAI-compatible endpoint, e.g. http://127.0.0.1:11434/v1.")
]
ModelNameOption = Annotated[
    str | None, typer.Option(help="Model name at the OpenAI-compatible endpoint, e.g. qwen3:8b.")
]
UrlOption = Annotated[
    str | None,
    typer.Option(
        "--url",
        help="Kernel URL (default: the running kernel of this data directory, else \\[kernel] host/port).",
    ),
]
