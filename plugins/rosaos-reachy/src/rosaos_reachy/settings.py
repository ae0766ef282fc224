"""The settings of one ``reachy`` instance (``[devices.NAME]``), and its ``sim`` table.

Keys for cloud engines can also come from the environment, the way their own SDKs read them:
``ELEVENLABS_API_KEY``, ``GROQ_API_KEY``, ``OPENAI_API_KEY`` (see :func:`env_secret`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, SecretStr, ValidationError

from rosaos.drivers import DeviceError, DeviceSettings

TtsEngineName = Literal["elevenlabs", "groq", "openai", "local"]
AudioOutput = Literal["auto", "robot", "host", "file"]
Physics = Literal["auto", "mujoco", "mockup"]

GROQ_BASE_URL = "https://api.groq.com/openai/v1"
ELEVENLABS_BASE_URL = "https://api.elevenlabs.io/v1"
EMOTIONS_DATASET = "pollen-robotics/reachy-mini-emotions-library"
DANCES_DATASET = "pollen-robotics/reachy-mini-dances-library"

Seconds = Annotated[float, Field(gt=0, le=600)]


class ReachySettings(DeviceSettings):
    """One Reachy Mini: where its daemon is (``real``), and which speech and vision engines to use."""

    # --- the real robot ---------------------------------------------------------------------
    host: str = Field(
        default="reachy-mini.local",
        description="Host of the Reachy Mini daemon: 'localhost' for a Lite on USB (the daemon runs "
        "on this computer), the robot's name or IP for a Wireless.",
    )
    daemon_port: Annotated[int, Field(ge=1, le=65535)] = Field(
        default=8000, description="Port of the daemon's API (reachy-mini-daemon --fastapi-port)."
    )
    connect_timeout: Seconds = Field(default=10.0, description="Seconds to wait for the daemon.")
    media: bool = Field(
        default=True,
        description="Use the robot's camera and speaker (real backend). False: no camera, speech "
        "plays on this computer.",
    )
    # --- companion --------------------------------------------------------------------------
    companion: bool = Field(
        default=True,
        description="Move on its own between tasks: breathe when idle, wave the antennas while listening, "
        "sway while speaking, turn to the speaker. It always yields to a process's motion.",
    )
    follow_face: bool = Field(
        default=True,
        description="While listening or speaking, keep facing the face the camera sees (the follow_face tool "
        "switches it at run time).",
    )
    # --- speech -----------------------------------------------------------------------------
    tts_engines: list[TtsEngineName] = Field(
        default=["elevenlabs", "groq", "openai", "local"],
        description="Text-to-speech engines, tried in order; one without a key is skipped. "
        "'local' (espeak-ng, offline) is always the last resort.",
    )
    audio_output: AudioOutput = Field(
        default="auto",
        description="Where speech plays: 'robot' speaker, 'host' audio device, or only a WAV 'file'; "
        "'auto' takes the first that exists, in that order.",
    )
    elevenlabs_api_key: SecretStr | None = Field(default=None, description="Default: $ELEVENLABS_API_KEY.")
    elevenlabs_voice: str = Field(default="JBFqnCBsd6RMkjVDRZzb", description="ElevenLabs voice id.")
    elevenlabs_model: str = "eleven_flash_v2_5"
    groq_api_key: SecretStr | None = Field(default=None, description="Default: $GROQ_API_KEY.")
    groq_tts_model: str = "canopylabs/orpheus-v1-english"
    groq_tts_voice: str = "autumn"
    tts_base_url: str | None = Field(
        default=None,
        description="Any OpenAI-compatible speech endpoint (POST <base>/audio/speech), for engine 'openai'.",
    )
    tts_api_key: SecretStr | None = Field(default=None, description="Default: $OPENAI_API_KEY.")
    tts_model: str = "tts-1"
    tts_voice: str = "alloy"
    local_voice: str | None = Field(
        default=None, description="espeak-ng voice for the local engine, e.g. 'gmw/en-us'."
    )
    local_rate: Annotated[int, Field(ge=80, le=400)] = Field(default=170, description="Words per minute.")
    tts_timeout: Seconds = 20.0
    # --- vision -----------------------------------------------------------------------------
    vision_base_url: str | None = Field(
        default=None,
        description="OpenAI-compatible chat endpoint with image input; default Groq's (needs a key).",
    )
    vision_model: str = "meta-llama/llama-4-scout-17b-16e-instruct"
    vision_api_key: SecretStr | None = Field(
        default=None, description="Default: $GROQ_API_KEY for Groq, $OPENAI_API_KEY otherwise."
    )
    vision_timeout: Seconds = 30.0
    # --- emotions ---------------------------------------------------------------------------
    emotions_dataset: str = Field(
        default=EMOTIONS_DATASET,
        description="Recorded emotions, used when already in the local Hugging Face cache (never downloaded).",
    )
    dances_dataset: str = DANCES_DATASET


class SimSettings(BaseModel):
    """The ``sim`` table: the initial state (``get_state`` keys) plus simulator-only settings."""

    model_config = ConfigDict(extra="forbid")

    head: dict[str, float] = Field(default_factory=dict)
    """Initial head pose: any of x, y, z (mm), roll, pitch, yaw (degrees); missing keys are 0."""
    antennas: tuple[float, float] | None = None
    """Initial [left, right] antenna angles in degrees; default the SDK's rest pose."""
    body_yaw: float = 0.0
    awake: bool = True
    last_spoken: str = ""
    physics: Physics = "auto"
    """'mujoco' (reachy-mini-daemon --sim), 'mockup' (--mockup-sim, no physics), 'auto': MuJoCo if installed."""
    camera_image: Path | None = None
    """A picture the simulated camera looks at (faces, a room); default a generated scene."""
    start_timeout: Seconds = 90.0
    """Seconds the simulated daemon may take to start."""

    @classmethod
    def from_sim(cls, instance: str, sim: dict[str, Any]) -> SimSettings:
        """Validate ``[devices.NAME.sim]``, raising :class:`DeviceError` naming the bad key."""
        try:
            settings = cls.model_validate(sim)
        except ValidationError as error:
            problems = "; ".join(f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in error.errors())
            raise DeviceError(
                f"[devices.{instance}.sim] {problems}; keys: head, antennas, body_yaw, awake, "
                "last_spoken, physics, camera_image, start_timeout"
            ) from None
        unknown = sorted(set(settings.head) - {"x", "y", "z", "roll", "pitch", "yaw"})
        if unknown:
            raise DeviceError(
                f"[devices.{instance}.sim] head: unknown keys {unknown}; use x, y, z, roll, pitch, yaw"
            )
        return settings


def env_secret(value: SecretStr | None, *names: str) -> str | None:
    """The configured secret, else the first of the environment variables ``names`` that is set."""
    if value is not None and value.get_secret_value():
        return value.get_secret_value()
    for name in names:
        if os.environ.get(name):
            return os.environ[name]
    return None
