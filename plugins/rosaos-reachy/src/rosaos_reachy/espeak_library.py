"""libespeak-ng in this process: the local voice where the ``espeak-ng`` command is missing.

Bound with ctypes to the library's C API, in its synchronous mode: ``espeak_Synth`` returns once
every sample has reached the callback, in the calling thread. pyttsx3 (used here before) runs the
library in its queued mode, where a rate is a command waiting in the library's own thread, and its
``runAndWait`` cancels that queue when the thread is still busy: on a loaded machine a sentence
then came out at the previous speaker's rate (CI: a rate-300 sentence as long as a rate-100 one).

The library holds one rate and one voice for the whole process, so :func:`synthesize` sets both
before every sentence, under one lock.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import threading

_SYNCHRONOUS = 2  # AUDIO_OUTPUT_SYNCHRONOUS
_RATE = 1  # espeakRATE, in words per minute
_CHARS_UTF8 = 0x1  # espeakCHARS_UTF8
_END_PAUSE = 0x1000  # espeakENDPAUSE: a short silence after the sentence, as the command adds
_POS_CHARACTER = 1
_DEFAULT_VOICE = "en"  # the espeak-ng command's default when no -v is given

_Callback = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int, ctypes.c_void_p)


class EspeakLibraryError(Exception):
    """libespeak-ng is missing or refused the request; the message says which."""


class _Library:
    """The loaded library: initialized once, as libespeak-ng allows one instance per process."""

    def __init__(self) -> None:
        name = ctypes.util.find_library("espeak-ng")
        if name is None:
            raise EspeakLibraryError("libespeak-ng is not installed")
        try:
            self.lib = ctypes.CDLL(name)
        except OSError as error:
            raise EspeakLibraryError(f"libespeak-ng did not load ({error})") from None
        self.lib.espeak_Initialize.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p, ctypes.c_int]
        self.lib.espeak_SetSynthCallback.argtypes = [_Callback]
        self.lib.espeak_SetVoiceByName.argtypes = [ctypes.c_char_p]
        self.lib.espeak_SetParameter.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int]
        self.lib.espeak_Synth.argtypes = [
            ctypes.c_char_p,
            ctypes.c_size_t,
            ctypes.c_uint,
            ctypes.c_int,
            ctypes.c_uint,
            ctypes.c_uint,
            ctypes.c_void_p,
            ctypes.c_void_p,
        ]
        self.sample_rate = int(self.lib.espeak_Initialize(_SYNCHRONOUS, 0, None, 0))
        if self.sample_rate <= 0:
            raise EspeakLibraryError("libespeak-ng did not initialize (is espeak-ng-data installed?)")
        self.chunks: list[bytes] = []
        self.callback = _Callback(self._collect)  # kept: the library holds only a raw pointer
        self.lib.espeak_SetSynthCallback(self.callback)

    def _collect(self, samples: ctypes._Pointer[ctypes.c_short], count: int, _events: int | None) -> int:
        if samples and count > 0:
            self.chunks.append(ctypes.string_at(samples, count * ctypes.sizeof(ctypes.c_short)))
        return 0  # go on


_LOCK = threading.Lock()
_library: _Library | None = None


def synthesize(text: str, rate: int, voice: str | None) -> tuple[bytes, int]:
    """The sentence as signed 16-bit mono PCM and its sample rate, at this rate and voice.

    ``voice`` is an espeak-ng voice name or file (``en-us``, ``gmw/en-us``); None is the default
    voice, set again here so that one speaker's voice does not stay for the next.
    """
    global _library
    with _LOCK:
        if _library is None:
            _library = _Library()
        library = _library
        wanted = voice or _DEFAULT_VOICE
        if library.lib.espeak_SetVoiceByName(wanted.encode()) != 0:
            raise EspeakLibraryError(f"libespeak-ng has no voice {wanted!r} (see `espeak-ng --voices`)")
        if library.lib.espeak_SetParameter(_RATE, rate, 0) != 0:
            raise EspeakLibraryError(f"libespeak-ng refused the rate {rate}")
        encoded = text.encode()
        library.chunks = []
        status = library.lib.espeak_Synth(
            encoded, len(encoded) + 1, 0, _POS_CHARACTER, 0, _CHARS_UTF8 | _END_PAUSE, None, None
        )
        pcm = b"".join(library.chunks)
        library.chunks = []
    if status != 0 or not pcm:
        raise EspeakLibraryError(f"libespeak-ng synthesized no audio (status {status})")
    return pcm, library.sample_rate
