"""Text-to-speech engines. Each turns text into WAV bytes, or says why it cannot.

- :class:`ElevenLabsTts`: ElevenLabs' REST API (raw 16 kHz PCM, wrapped as WAV here).
- :class:`OpenAISpeechTts`: any OpenAI-compatible ``POST /audio/speech``; Groq's is one of them.
- :class:`LocalTts`: espeak-ng, entirely offline. Always available on Debian with the
  ``espeak-ng`` package; libespeak-ng in process is the fallback where the command is missing.
"""

from __future__ import annotations

import asyncio
import io
import shutil
import subprocess
import tempfile
import wave
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Protocol

import httpx

from rosaos_reachy import espeak_library
from rosaos_reachy.espeak_library import EspeakLibraryError
from rosaos_reachy.settings import ELEVENLABS_BASE_URL, GROQ_BASE_URL, ReachySettings, env_secret


class TtsError(Exception):
    """An engine failed; the message says what the service answered."""


class TtsEngine(Protocol):
    """A text-to-speech engine."""

    name: str

    def unavailable(self) -> str | None:
        """None when the engine can be tried; otherwise why not (e.g. no key)."""
        ...

    async def synthesize(self, text: str) -> bytes:
        """The speech as WAV bytes; raises :class:`TtsError`."""
        ...


def wav_from_pcm(pcm: bytes, rate: int, channels: int = 1) -> bytes:
    """Wrap signed 16-bit little-endian PCM as a WAV file."""
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as out:
        out.setnchannels(channels)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes(pcm)
    return buffer.getvalue()


def wav_duration(data: bytes) -> float:
    """Length of a WAV file in seconds."""
    try:
        with wave.open(io.BytesIO(data)) as wav:
            return wav.getnframes() / float(wav.getframerate())
    except (wave.Error, EOFError) as error:
        raise TtsError(f"the engine did not return a WAV file ({error})") from None


class ElevenLabsTts:
    """ElevenLabs text-to-speech (https://elevenlabs.io), with ``ELEVENLABS_API_KEY``."""

    name = "elevenlabs"
    rate = 16000

    def __init__(self, settings: ReachySettings, base_url: str = ELEVENLABS_BASE_URL) -> None:
        self.key = env_secret(settings.elevenlabs_api_key, "ELEVENLABS_API_KEY")
        self.voice = settings.elevenlabs_voice
        self.model = settings.elevenlabs_model
        self.timeout = settings.tts_timeout
        self.base_url = base_url.rstrip("/")

    def unavailable(self) -> str | None:
        return None if self.key else "no key: set ELEVENLABS_API_KEY or elevenlabs_api_key"

    async def synthesize(self, text: str) -> bytes:
        url = f"{self.base_url}/text-to-speech/{self.voice}"
        async with httpx.AsyncClient(timeout=self.timeout) as http:
            response = await http.post(
                url,
                params={"output_format": f"pcm_{self.rate}"},
                headers={"xi-api-key": self.key or ""},
                json={"text": text, "model_id": self.model},
            )
        _raise_for(response, "ElevenLabs")
        return wav_from_pcm(response.content, self.rate)


class OpenAISpeechTts:
    """An OpenAI-compatible ``/audio/speech`` endpoint: Groq's, OpenAI's, or a local server's."""

    def __init__(
        self, name: str, base_url: str | None, key: str | None, model: str, voice: str, timeout: float
    ) -> None:
        self.name = name
        self.base_url = base_url.rstrip("/") if base_url else None
        self.key = key
        self.model = model
        self.voice = voice
        self.timeout = timeout

    @classmethod
    def groq(cls, settings: ReachySettings) -> OpenAISpeechTts:
        key = env_secret(settings.groq_api_key, "GROQ_API_KEY")
        return cls(
            "groq", GROQ_BASE_URL, key, settings.groq_tts_model, settings.groq_tts_voice, settings.tts_timeout
        )

    @classmethod
    def openai_compatible(cls, settings: ReachySettings) -> OpenAISpeechTts:
        key = env_secret(settings.tts_api_key, "OPENAI_API_KEY")
        return cls(
            "openai", settings.tts_base_url, key, settings.tts_model, settings.tts_voice, settings.tts_timeout
        )

    def unavailable(self) -> str | None:
        if self.base_url is None:
            return "no endpoint: set tts_base_url (e.g. http://127.0.0.1:8880/v1)"
        if self.name == "groq" and not self.key:
            return "no key: set GROQ_API_KEY or groq_api_key"
        return None

    async def synthesize(self, text: str) -> bytes:
        headers = {"Authorization": f"Bearer {self.key}"} if self.key else {}
        body = {"model": self.model, "input": text, "voice": self.voice, "response_format": "wav"}
        async with httpx.AsyncClient(timeout=self.timeout) as http:
            response = await http.post(f"{self.base_url}/audio/speech", headers=headers, json=body)
        _raise_for(response, self.name)
        wav_duration(response.content)  # validates it is a WAV file
        return response.content


class LocalTts:
    """espeak-ng: offline, instant, robotic.

    The ``espeak-ng`` command is run once per sentence, with this speaker's rate and voice on its
    command line (about 10 ms for a sentence). Where the command is missing, libespeak-ng speaks
    in this process (:mod:`rosaos_reachy.espeak_library`), with the rate and voice set again before
    each sentence: the library keeps one of each for the whole process.
    """

    name = "local"

    def __init__(self, settings: ReachySettings) -> None:
        self.voice = settings.local_voice
        self.rate = settings.local_rate
        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rosaos-tts")

    def unavailable(self) -> str | None:
        return None  # tried last; synthesize says what is missing

    async def synthesize(self, text: str) -> bytes:
        return await asyncio.get_running_loop().run_in_executor(self._thread, self._synthesize, text)

    def _synthesize(self, text: str) -> bytes:
        program = shutil.which("espeak-ng") or shutil.which("espeak")
        if program is None:
            try:
                pcm, sample_rate = espeak_library.synthesize(text, self.rate, self.voice)
            except EspeakLibraryError as error:
                raise TtsError(f"no espeak-ng command, and {error}: apt-get install espeak-ng") from None
            return wav_from_pcm(pcm, sample_rate)
        with tempfile.TemporaryDirectory(prefix="rosaos-tts-") as tmp:
            path = Path(tmp) / "speech.wav"
            self._espeak_cli(program, text, path)
            data = path.read_bytes()
        wav_duration(data)
        return data

    def _espeak_cli(self, program: str, text: str, path: Path) -> None:
        command = [program, "-s", str(self.rate), "-w", str(path)]
        if self.voice:
            command += ["-v", self.voice.split("/")[-1]]
        # "--" ends the options: a sentence that starts with "-" is spoken, not read as a flag.
        result = subprocess.run([*command, "--", text], capture_output=True, timeout=60, check=False)
        if result.returncode != 0 or not path.is_file():
            raise TtsError(f"espeak-ng failed: {result.stderr.decode(errors='replace').strip()}")


def build_engines(settings: ReachySettings) -> list[TtsEngine]:
    """The engines in the configured order, with the local one always last."""
    factories: dict[str, Callable[[], TtsEngine]] = {
        "elevenlabs": lambda: ElevenLabsTts(settings),
        "groq": lambda: OpenAISpeechTts.groq(settings),
        "openai": lambda: OpenAISpeechTts.openai_compatible(settings),
        "local": lambda: LocalTts(settings),
    }
    names = [name for name in dict.fromkeys(settings.tts_engines) if name != "local"] + ["local"]
    return [factories[name]() for name in names]


def _raise_for(response: httpx.Response, service: str) -> None:
    if response.status_code >= 400:
        detail = response.text[:200].strip()
        raise TtsError(f"{service} answered HTTP {response.status_code}: {detail}")
