"""Speech-to-text engines: Moonshine offline on onnxruntime (the default), Groq, any OpenAI-compatible endpoint.

Each takes one utterance (mono float32 at 16 kHz) and returns its transcript. The local engine
runs in a worker thread, so the event loop keeps reading audio while it thinks.
"""

from __future__ import annotations

import asyncio
import io
import os
import threading
import wave
from typing import Protocol

import httpx
import numpy as np

from rosaos.config import VoiceConfig
from rosaos.frontends.voice.sources import SAMPLE_RATE, Samples, VoiceError
from rosaos.frontends.voice.word_bias import Bias
from rosaos.native import probe

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
    """Moonshine base (English) on onnxruntime: the weights ship inside a wheel, no network.

    Before loading it in this process, the engine is loaded once in a child process
    (:func:`rosaos.native.probe`): a native library that does not fit this CPU then becomes a
    message naming it and the cloud engines, not a dead ``rosaos voice``.
    """

    name = "local (moonshine base-en)"

    def __init__(self, language: str = "en", probe_first: bool = True) -> None:
        if language != "en":
            raise VoiceError(
                f"the local engine (Moonshine) is English-only, not {language!r}: "
                "set [voice] stt = 'groq' or 'openai' for other languages"
            )
        from rosaos.frontends.voice.moonshine import MoonshineOnnx

        if probe_first:
            check = probe(
                "onnxruntime (Moonshine speech-to-text)",
                "import numpy as np\n"
                "from rosaos.frontends.voice.moonshine import MoonshineOnnx\n"
                "MoonshineOnnx().transcribe(np.zeros(8000, dtype=np.float32))\n",
            )
            if not check.ok:
                raise VoiceError(
                    f"{check.explain()}. Use a cloud engine instead: [voice] stt = 'groq' "
                    "(GROQ_API_KEY) or stt = 'openai' (OPENAI_API_KEY, or stt_base_url for a local server)"
                )
        self._engine = MoonshineOnnx()
        self._lock = threading.Lock()  # one decoder cache at a time

    def bias_toward(self, phrases: list[str]) -> None:
        """Hear these words (device names, rooms, catalog entries) more readily; [] to stop."""
        self._engine.bias = Bias(phrases) if phrases else None

    async def transcribe(self, samples: Samples) -> str:
        return await asyncio.to_thread(self.transcribe_sync, samples)

    def transcribe_sync(self, samples: Samples) -> str:
        """Blocking transcription (benchmarks time it directly)."""
        audio = np.ascontiguousarray(samples, dtype=np.float32)
        if audio.size < SAMPLE_RATE // 10:  # under 0.1 s: the model only hallucinates on these
            return ""
        with self._lock:
            return self._engine.transcribe(audio)


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


def word_error_rate(reference: str, hypothesis: str) -> float:
    """Word edits (substitutions, insertions, deletions) per reference word, on normalized text."""
    from rosaos.frontends.voice.wake import normalize

    def words(text: str) -> list[str]:
        return normalize(text.replace("%", " percent")).split()

    ref, hyp = words(reference), words(hypothesis)
    previous = list(range(len(hyp) + 1))
    for i, word in enumerate(ref, 1):
        current = [i]
        for j, heard in enumerate(hyp, 1):
            current.append(min(previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (word != heard)))
        previous = current
    return previous[-1] / max(1, len(ref))


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
