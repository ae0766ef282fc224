"""Speech-to-text engines: Moonshine offline (the default), Groq, any OpenAI-compatible endpoint.

Each takes one utterance (mono float32 at 16 kHz) and returns its transcript. The local engine
runs in a worker thread, so the event loop keeps reading audio while it thinks.
"""

from __future__ import annotations

import asyncio
import ctypes
import io
import os
import threading
import wave
from typing import Any, Protocol

import httpx
import numpy as np

from rosaos.config import VoiceConfig
from rosaos.frontends.voice.sources import SAMPLE_RATE, Samples, VoiceError

GROQ_BASE_URL = "https://api.groq.com/openai/v1"
GROQ_MODEL = "whisper-large-v3-turbo"
OPENAI_BASE_URL = "https://api.openai.com/v1"
OPENAI_MODEL = "whisper-1"


class SpeechToText(Protocol):
    """Turns one utterance into text."""

    name: str
    """Shown to the user: ``local (moonshine base-en)``, ``groq (whisper-large-v3-turbo)``."""

    async def transcribe(self, samples: Samples) -> str: ...


class MoonshineSTT:
    """Moonshine base (English) through moonshine-cpp: the weights ship inside the wheel, no network.

    Calls the library's C function directly: the wheel's own ``MoonshineModel.transcribe`` refers
    to ``ctypes.c_float_p``, which does not exist, so only its WAV-file path works.
    """

    name = "local (moonshine base-en)"

    def __init__(self, language: str = "en") -> None:
        if language != "en":
            raise VoiceError(
                f"the local engine (Moonshine) is English-only, not {language!r}: "
                "set [voice] stt = 'groq' or 'openai' for other languages"
            )
        try:
            import moonshine_cpp
        except ImportError:
            raise VoiceError(
                "the local speech-to-text engine needs moonshine-cpp: pip install 'rosaos[voice]'"
            ) from None
        except OSError as error:  # its bundled shared libraries failed to load
            raise VoiceError(f"moonshine-cpp is installed but cannot load: {error}") from None
        self._lib: Any = moonshine_cpp.moonshine_lib
        self._model = moonshine_cpp.MoonshineModel()  # the bundled models/base-en
        self._lock = threading.Lock()  # one model handle: one transcription at a time

    async def transcribe(self, samples: Samples) -> str:
        return await asyncio.to_thread(self.transcribe_sync, samples)

    def transcribe_sync(self, samples: Samples) -> str:
        """Blocking transcription (benchmarks time it directly)."""
        audio = np.ascontiguousarray(samples, dtype=np.float32)
        if audio.size < SAMPLE_RATE // 10:  # under 0.1 s: the model only hallucinates on these
            return ""
        text = ctypes.c_char_p()
        with self._lock:
            error = self._lib.moonshine_transcribe(
                self._model.model_handle,
                audio.ctypes.data_as(ctypes.POINTER(ctypes.c_float)),
                audio.size,
                ctypes.byref(text),
            )
            if error != 0:
                raise VoiceError(f"Moonshine could not transcribe the utterance (error {error})")
            result = (text.value or b"").decode("utf-8", errors="replace")
            self._lib.moonshine_free_text(text)
        return result.strip()


class OpenAITranscriptionSTT:
    """``POST {base_url}/audio/transcriptions``: OpenAI, Groq, and the many servers that copy them."""

    def __init__(
        self,
        label: str,
        base_url: str,
        model: str,
        api_key: str | None,
        language: str = "en",
        timeout: float = 30.0,
    ) -> None:
        self.name = f"{label} ({model})"
        self.url = base_url.rstrip("/") + "/audio/transcriptions"
        self.model = model
        self.language = language
        headers = {"Authorization": f"Bearer {api_key}"} if api_key else {}
        self._http = httpx.AsyncClient(headers=headers, timeout=httpx.Timeout(timeout))

    async def transcribe(self, samples: Samples) -> str:
        files = {"file": ("utterance.wav", wav_bytes(samples), "audio/wav")}
        data = {"model": self.model, "language": self.language, "response_format": "json"}
        try:
            response = await self._http.post(self.url, files=files, data=data)
        except httpx.TimeoutException:
            raise VoiceError(
                f"{self.url} did not answer in time; try again or raise [voice] stt_timeout"
            ) from None
        except httpx.HTTPError as error:
            raise VoiceError(f"cannot reach {self.url} ({error}); check [voice] stt_base_url") from None
        if response.status_code in (401, 403):
            raise VoiceError(
                f"{self.url} refused the key ({response.status_code}): check [voice] stt_api_key"
            )
        if response.status_code >= 400:
            raise VoiceError(f"{self.url} failed with {response.status_code}: {response.text[:300]}")
        try:
            return str(response.json()["text"]).strip()
        except (ValueError, KeyError, TypeError):
            raise VoiceError(f"{self.url} answered without a 'text' field: {response.text[:300]}") from None

    async def aclose(self) -> None:
        await self._http.aclose()


def wav_bytes(samples: Samples) -> bytes:
    """16-bit mono 16 kHz WAV, what every transcription endpoint accepts."""
    pcm = (np.clip(samples, -1, 1) * 32767).astype("<i2")
    buffer = io.BytesIO()
    with wave.open(buffer, "wb") as wav:
        wav.setnchannels(1)
        wav.setsampwidth(2)
        wav.setframerate(SAMPLE_RATE)
        wav.writeframes(pcm.tobytes())
    return buffer.getvalue()


def build_stt(config: VoiceConfig) -> SpeechToText:
    """The engine ``[voice] stt`` names, with its key from the config or the usual variable."""
    if config.stt == "local":
        return MoonshineSTT(config.language)
    if config.stt == "groq":
        key = config.stt_api_key or os.environ.get("GROQ_API_KEY")
        if not key:
            raise VoiceError("stt = 'groq' needs a key: set GROQ_API_KEY, or [voice] stt_api_key")
        return OpenAITranscriptionSTT(
            "groq",
            config.stt_base_url or GROQ_BASE_URL,
            config.stt_model or GROQ_MODEL,
            key,
            config.language,
            config.stt_timeout,
        )
    key = config.stt_api_key or os.environ.get("OPENAI_API_KEY")
    if config.stt_base_url is None and not key:
        raise VoiceError(
            "stt = 'openai' needs [voice] stt_base_url (a local server) or a key (OPENAI_API_KEY)"
        )
    return OpenAITranscriptionSTT(
        "openai-compatible",
        config.stt_base_url or OPENAI_BASE_URL,
        config.stt_model or OPENAI_MODEL,
        key,
        config.language,
        config.stt_timeout,
    )
