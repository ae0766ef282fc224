"""Configuration: ``rosaos.toml`` plus ``ROSAOS_*`` environment variables, via pydantic-settings.

The file is found in this order: ``--config PATH``, then ``$ROSAOS_CONFIG``, then
``./rosaos.toml``, then ``<user config dir>/rosaos/rosaos.toml``. No file is fine: the demo world
is used. Environment variables override the file; nested keys use ``__``
(``ROSAOS_KERNEL__PORT=9000``).

A bad file fails at start with :class:`ConfigError`, naming the file, the key and the reason.
"""

from __future__ import annotations

import os
import tomllib
from contextvars import ContextVar
from pathlib import Path
from typing import Any, Literal

import platformdirs
from pydantic import BaseModel, ConfigDict, Field, PrivateAttr, ValidationError
from pydantic_settings import (
    BaseSettings,
    PydanticBaseSettingsSource,
    SettingsConfigDict,
    TomlConfigSettingsSource,
)

CONFIG_ENV = "ROSAOS_CONFIG"
CONFIG_FILENAME = "rosaos.toml"
DEFAULT_KERNEL_PORT = 8765


class ConfigError(Exception):
    """Configuration that cannot be used. The message names the file, the key and the reason."""


class MapOrigin(BaseModel):
    """Where a robot's own odometry frame sits in the shared floor map: its start pose there."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    x: float = 0.0
    """Metres, in the map's frame."""
    y: float = 0.0
    yaw: float = 0.0
    """Radians: the map heading of the robot's own x axis."""


class DeviceConfig(BaseModel):
    """One ``[devices.NAME]`` table. Keys not listed here are the driver's own settings.

    The keys below are reserved for rosaOS: a driver's settings model must not use them (the
    conformance kit checks), because the driver would never see their values.
    """

    model_config = ConfigDict(extra="allow")

    driver: str
    backend: Literal["sim", "real"] = "sim"
    """``sim`` unless you say otherwise: rosaOS never actuates hardware you did not opt into."""
    description: str | None = None
    """Overrides the driver's description; the kernel reads it to pick devices."""
    aliases: list[str] = Field(default_factory=list)
    """Other names people use for it ("the lamp"); the instance name with spaces is always one."""
    area: str | None = None
    """Room it is in ("kitchen"), for "turn off the kitchen lights"; guessed from the description when unset."""
    url: str | None = None
    """A remote instance served elsewhere by ``rosaos serve-device``; no local process is started."""
    token: str | None = None
    """Bearer token of a remote instance; defaults to this machine's token."""
    port: int | None = Field(default=None, ge=1, le=65535)
    """Fixed loopback port for a local instance; a free port is chosen when unset."""
    sim: dict[str, Any] = Field(default_factory=dict)
    map_origin: MapOrigin | None = None
    """A mobile robot's pose in the shared floor map (``{x = 2.0, y = -1.0, yaw = 1.57}``): each
    robot reports positions in its own odometry frame, which starts wherever it was switched on;
    the web page draws every robot, trail and person in the map frame through this."""
    confirm: list[str] | Literal["destructive", "off"] | None = None
    """Tools that need a person's yes before they run: names, ``"destructive"`` (every tool
    annotated destructiveHint) or ``"off"``. Unset: the global ``confirm``, else on
    (destructive) for a real ROS robot and off for simulators."""
    """Initial simulator state and sim-only settings."""

    def driver_settings(self) -> dict[str, Any]:
        """The keys that belong to the driver's own settings model."""
        return dict(self.model_extra or {})


class KernelConfig(BaseModel):
    """``[kernel]``: the event queue, the kernel agent and the worker pool."""

    model_config = ConfigDict(extra="forbid")

    host: str = "127.0.0.1"
    port: int = Field(default=DEFAULT_KERNEL_PORT, ge=0, le=65535)
    """Port for the API and web page; 0 picks a free one (printed at start)."""
    allow_hosts: list[str] = Field(default_factory=list)
    """``Host`` names the API answers to besides loopback (and the address it binds): against DNS
    rebinding, any other name gets 421. E.g. ``["rosaos-desk.local"]`` to open it by that name."""
    pool_size: int = Field(default=2, ge=0, le=32)
    """Warm worker subprocesses kept ready. A one-off worker is spawned when all are busy."""
    fork_server: bool = True
    """Fork one-off workers from a pre-imported fork server (milliseconds instead of seconds);
    it costs one more process of about a warm worker's memory. Off: one-offs start a new Python."""
    max_workers: int | None = Field(default=None, ge=1, le=1024)
    """Processes that may run at once; more wait in a queue, in order, and are not refused.
    Unset: sized to the machine (6 per core, as many as the available memory holds at 64 MiB)."""
    job_timeout: float = Field(default=300.0, gt=0, le=3600)
    confirm_timeout: float = Field(default=30.0, gt=0, le=600)
    """Seconds a confirmation question waits for a yes; silence is a no."""
    """Seconds a process agent may run before it is killed and its leases released."""
    request_limit: int = Field(default=30, ge=1, le=1000)
    """Model requests one process agent may make (pydantic-ai usage limit)."""
    history_messages: int = Field(default=40, ge=2, le=1000)
    """Kernel conversation budget: older messages are trimmed beyond this many."""
    history_chars: int = Field(default=4000, ge=1000, le=1_000_000)
    """Kernel conversation budget in characters (about 4 per token): every request carries it."""
    relay_reports: bool = True
    """With an LLM kernel: a process that ended ok, with no follow-up waiting, is relayed to the
    user in its own words without a kernel model request (the callback still enters the history)."""
    kernel_prompt: str | None = None
    """Replaces the built-in kernel prompt; ``{devices}`` is filled with the device list."""
    process_prompt: str | None = None
    """Replaces the built-in base process prompt."""


class ModelConfig(BaseModel):
    """``[models]``: which model the kernel and the process agents use.

    ``kernel``/``process`` take any pydantic-ai model string (``openai:gpt-5.2``,
    ``anthropic:...``, ``google:...``, ``groq:...``), or ``openai-compatible`` together with
    ``base_url`` and ``model_name`` (vLLM, Ollama, llama.cpp). Unset means the offline default.
    Keys come from the provider's usual environment variable (``OPENAI_API_KEY``, ...).
    """

    model_config = ConfigDict(extra="forbid")

    kernel: str | None = None
    process: str | None = None
    base_url: str | None = None
    api_key: str | None = None
    model_name: str | None = None
    prefer_local: bool = True
    language: str = "en"
    vision: bool | None = None
    """Whether the process model takes images (camera tools then send the picture too).
    Unset: only a cloud provider's model whose pydantic-ai profile says so (``supports_image_input``);
    an ``openai-compatible`` endpoint must declare it."""
    image_max_px: int = Field(default=768, ge=64, le=4096)
    """Longest side, in pixels, of a picture sent to a model (a JPEG of at most ~400 kB)."""


class MemoryConfig(BaseModel):
    """``[memory]``: how long what the robots saw is kept (places and what people said stay until forgotten)."""

    model_config = ConfigDict(extra="forbid")

    sightings_days: float = Field(default=7.0, gt=0, le=3650)
    """Days a sighting (a person a robot's camera found) is kept."""


class VoiceConfig(BaseModel):
    """``[voice]``: the voice front end, ``rosaos voice``: audio source, VAD, wake, speech-to-text.

    Everything works offline with the defaults: Silero VAD and the Moonshine model ship inside
    their wheels (``pip install 'rosaos[voice]'``).
    """

    model_config = ConfigDict(extra="forbid")

    source: Literal["mic", "reachy"] = "mic"
    """Where audio comes from: the host microphone, or the Reachy Mini's microphone array."""
    reachy_host: str = "reachy-mini.local"
    """Host of the Reachy Mini daemon for ``source = "reachy"``: ``localhost`` for a Lite on USB."""
    reachy_port: int = Field(default=8000, ge=1, le=65535)
    """Port of the daemon's API (``reachy-mini-daemon --fastapi-port``)."""
    vad: Literal["silero", "energy"] = "silero"
    """Voice activity detection: Silero (ignores tones, fans and noise), or a plain loudness threshold."""
    vad_threshold: float = Field(default=0.5, gt=0, lt=1)
    """Silero speech probability above which a frame counts as speech."""
    energy_threshold_db: float = Field(default=-40.0, ge=-90, le=0)
    """For ``vad = "energy"``: frames louder than this (dBFS) count as speech."""
    silence_seconds: float = Field(default=0.55, ge=0.1, le=5)
    """Silence that ends an utterance."""
    complete_silence_seconds: float = Field(default=0.18, ge=0.06, le=5)
    """Silence that ends an utterance already heard as a whole command (the offline engine judges
    the draft transcript; needs ``early_transcription``). Not above ``silence_seconds``."""
    min_speech_seconds: float = Field(default=0.35, ge=0.05, le=5)
    """Shorter bursts of speech (coughs, clicks) are dropped."""
    chunk_seconds: float = Field(default=0.032, ge=0.02, le=1)
    """Audio is processed in chunks this long; end-of-speech is noticed within one chunk."""
    max_utterance_seconds: float = Field(default=20.0, ge=1, le=120)
    """An utterance is cut here even if the speaker has not paused."""
    wake: Literal["phrase", "eye_contact", "either", "off"] = "phrase"
    """What wakes the robot: the wake phrase, a face looking at its camera, either, or nothing needed."""
    wake_phrase: str = "hello"
    wake_aliases: list[str] = Field(default_factory=lambda: ["hallo", "hullo", "hey rosa", "hi rosa"])
    """Other phrases that wake it too, e.g. how your STT engine spells the wake phrase."""
    follow_up_seconds: float = Field(default=8.0, ge=0, le=120)
    """After a wake or a command, keep listening this long without the wake phrase."""
    eye_contact_frames: int = Field(default=5, ge=1, le=100)
    """Consecutive camera frames with a face that count as eye contact."""
    stt: Literal["local", "groq", "openai"] = "local"
    """Speech-to-text: ``local`` (Moonshine, offline), ``groq`` (whisper-large-v3-turbo), or
    ``openai``: any OpenAI-compatible ``/audio/transcriptions`` endpoint (``stt_base_url``)."""
    stt_model: str | None = None
    """Model at the cloud endpoint; default ``whisper-large-v3-turbo`` (groq) or ``whisper-1``."""
    stt_base_url: str | None = None
    """OpenAI-compatible endpoint, e.g. ``http://127.0.0.1:8000/v1``; Groq's by default for groq."""
    stt_api_key: str | None = None
    """Key for the cloud endpoint; default from ``GROQ_API_KEY`` or ``OPENAI_API_KEY``."""
    stt_timeout: float = Field(default=30.0, gt=0, le=300)
    language: str = "en"
    """Spoken language (the local engine is English-only)."""
    vocabulary_bias: bool = True
    """The local engine hears this world's words more readily: device names and aliases, rooms,
    catalog tracks and artists, command words ("turtlebot", not "turtle not")."""
    speak_replies: bool = True
    """Say the kernel's replies to what was heard through the Reachy Mini's ``speak`` (when served)."""
    early_transcription: bool = True
    """Start transcribing once the speaker has paused briefly, while waiting for ``silence_seconds``
    to be sure the utterance ended; the transcript is ready sooner, and a whole command ends the
    turn after ``complete_silence_seconds``. Local engine only (a cloud engine would be sent every
    pause)."""
    barge_in: bool = True
    """Let the user talk over the robot: it stops speaking and listens (a live source only)."""
    barge_in_margin_db: float = Field(default=10.0, ge=0, le=40)
    """How much louder than the robot's own voice at the microphones the user must be to barge in."""
    barge_in_min_seconds: float = Field(default=0.1, ge=0.03, le=1)
    """Speech over the robot for this long stops it (shorter is a cough)."""


def default_data_dir() -> Path:
    return Path(platformdirs.user_data_dir("rosaos", appauthor=False))


def user_config_file() -> Path:
    return Path(platformdirs.user_config_dir("rosaos", appauthor=False)) / CONFIG_FILENAME


_config_file: ContextVar[Path | None] = ContextVar("rosaos_config_file", default=None)


class RosaosConfig(BaseSettings):
    """The whole configuration. Build it with :func:`load_config`."""

    model_config = SettingsConfigDict(env_prefix="ROSAOS_", env_nested_delimiter="__", extra="forbid")

    data_dir: Path = Field(default_factory=default_data_dir)
    """Event store, token, caches and images. Default: the user data directory."""
    devices: dict[str, DeviceConfig] = Field(default_factory=dict)
    confirm: list[str] | Literal["destructive", "off"] | None = None
    """What needs a yes on every device without its own ``confirm`` (see DeviceConfig.confirm)."""
    kernel: KernelConfig = Field(default_factory=KernelConfig)
    models: ModelConfig = Field(default_factory=ModelConfig)
    voice: VoiceConfig = Field(default_factory=VoiceConfig)
    memory: MemoryConfig = Field(default_factory=MemoryConfig)

    @classmethod
    def settings_customise_sources(
        cls,
        settings_cls: type[BaseSettings],
        init_settings: PydanticBaseSettingsSource,
        env_settings: PydanticBaseSettingsSource,
        dotenv_settings: PydanticBaseSettingsSource,
        file_secret_settings: PydanticBaseSettingsSource,
    ) -> tuple[PydanticBaseSettingsSource, ...]:
        sources: list[PydanticBaseSettingsSource] = [init_settings, env_settings]
        path = _config_file.get()
        if path is not None:
            sources.append(TomlConfigSettingsSource(settings_cls, toml_file=path))
        return tuple(sources)

    _source: Path | None = PrivateAttr(default=None)

    @property
    def source(self) -> Path | None:
        """The config file this came from; None when there was none (the demo world)."""
        return self._source

    @property
    def token_file(self) -> Path:
        return self.data_dir / "token"


def find_config_file(explicit: Path | None = None) -> Path | None:
    """Locate ``rosaos.toml``: explicit path, ``$ROSAOS_CONFIG``, working dir, user config dir."""
    if explicit is not None:
        if not explicit.is_file():
            raise ConfigError(f"{explicit}: no such config file")
        return explicit
    from_env = os.environ.get(CONFIG_ENV)
    if from_env:
        path = Path(from_env)
        if not path.is_file():
            raise ConfigError(f"{path}: no such config file (from ${CONFIG_ENV})")
        return path
    for candidate in (Path.cwd() / CONFIG_FILENAME, user_config_file()):
        if candidate.is_file():
            return candidate
    return None


def load_config(explicit: Path | None = None, **overrides: Any) -> RosaosConfig:
    """Find, read and validate the configuration. ``overrides`` win over file and env."""
    path = find_config_file(explicit)
    where = str(path) if path else "environment"
    if path is not None:
        try:
            tomllib.loads(path.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as error:
            raise ConfigError(f"{path}: not valid TOML: {error}") from None
    token = _config_file.set(path)
    try:
        config = RosaosConfig(**overrides)
    except ValidationError as error:
        raise ConfigError(format_validation_error(where, error)) from None
    finally:
        _config_file.reset(token)
    config._source = path
    return config


def format_validation_error(where: str, error: ValidationError, prefix: str = "") -> str:
    """One line per problem: ``file: key.path: reason``."""
    lines = []
    for problem in error.errors():
        key = ".".join(str(part) for part in problem["loc"])
        key = f"{prefix}.{key}" if prefix and key else (prefix or key)
        lines.append(f"{where}: {key}: {problem['msg']}")
    return "\n".join(lines)
