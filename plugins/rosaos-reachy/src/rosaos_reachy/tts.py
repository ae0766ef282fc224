"""Text-to-speech engines. Each turns text into WAV bytes, or says why it cannot.

- :class:`ElevenLabsTts`: ElevenLabs' REST API (raw 16 kHz PCM, wrapped as WAV here).
- :class:`OpenAISpeechTts`: any OpenAI-compatible ``POST /audio/speech``; Groq's is one of them.
- :class:`LocalTts`: espeak-ng, entirely offline. Always available on Debian with the
  ``espeak-ng`` package; pyttsx3 over libespeak-ng is the fallback where the command is missing.
"""

from __future__ import annotations

import asyncio
import io
import shutil
import subprocess
import tempfile
import threading
import wave
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any, Protocol

import httpx

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
    command line (about 10 ms for a sentence, as fast as the library in process). In process,
    libespeak-ng keeps one rate and voice for the whole process and pyttsx3 hands every caller the
    same engine, so two speakers could hear each other's settings (CI run 11: a rate-100 and a
    rate-300 sentence came out the same length); the library is used only where the command is
    missing, one sentence at a time, on one thread.
    """

    name = "local"

    def __init__(self, settings: ReachySettings) -> None:
        self.voice = settings.local_voice
        self.rate = settings.local_rate
        self._thread = ThreadPoolExecutor(max_workers=1, thread_name_prefix="rosaos-tts")
        self._engine: Any = None

    def unavailable(self) -> str | None:
        return None  # tried last; synthesize says what is missing

    async def synthesize(self, text: str) -> bytes:
        return await asyncio.get_running_loop().run_in_executor(self._thread, self._synthesize, text)

    def _synthesize(self, text: str) -> bytes:
        with tempfile.TemporaryDirectory(prefix="rosaos-tts-") as tmp:
            path = Path(tmp) / "speech.wav"
            program = shutil.which("espeak-ng") or shutil.which("espeak")
            if program is not None:
                self._espeak_cli(program, text, path)
            else:
                problem = self._pyttsx3(text, path)
                if problem is not None:
                    raise TtsError(f"no espeak-ng command, and {problem}: apt-get install espeak-ng")
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

    def _pyttsx3(self, text: str, path: Path) -> str | None:
        with _LIBRARY_LOCK:
            try:
                import pyttsx3  # imported here: it loads libespeak-ng at import

                if self._engine is None:
                    self._engine = pyttsx3.init("espeak")
                engine = self._engine
                engine.setProperty("rate", self.rate)
                if self.voice:
                    engine.setProperty("voice", self.voice)
                engine.save_to_file(text, str(path))
                engine.runAndWait()
            except Exception as error:  # a missing libespeak-ng shows up as OSError/RuntimeError
                self._engine = None
                return f"pyttsx3: {type(error).__name__}: {error}"
        if not path.is_file() or path.stat().st_size <= 44:
            return "pyttsx3 wrote no audio"
        return None


_LIBRARY_LOCK = threading.Lock()
"""libespeak-ng is one engine per process: one sentence at a time across every speaker."""


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
