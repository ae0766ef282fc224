"""Moonshine base (English) on the official onnxruntime wheel: the offline speech-to-text engine.

The weights are the ones the ``moonshine-cpp`` wheel ships (ORT-format encoder and merged decoder,
and its tokenizer), rewritten once into ONNX that uses each int8 weight only where it is read
(:mod:`rosaos.frontends.voice.onnx_graph`: 414 → 233 MiB peak; the decoder multiplies in int8,
a fifth of the time a step took with float copies of its weights). Only its
data files are read: its own ``libmoonshine.so`` was built for CPUs
with AVX-512 and dies with SIGILL on the many that lack it (AMD before Zen 4, most laptops), so
the package is never imported. onnxruntime picks its kernels by CPU feature at run time.

Decoding is greedy: the encoder reads the samples once, then the merged decoder emits one token a
step, reusing its key/value cache (``use_cache_branch``), until end-of-text or a length bound that
grows with the audio's duration (Moonshine's own rule of thumb: about 6 tokens a second).
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from rosaos.frontends.voice.onnx_graph import converted
from rosaos.frontends.voice.sources import SAMPLE_RATE, Samples, VoiceError
from rosaos.frontends.voice.word_bias import Bias

WEIGHTS_PACKAGE = "moonshine-cpp"
"""The PyPI package whose wheel carries the weights (``pip install 'rosaos[voice]'``)."""
MODEL_DIR = ("models", "base-en")
BOS, EOS = 1, 2
TOKENS_PER_SECOND = 6.5
"""Upper bound of tokens per second of speech; stops a decoder that never says end-of-text."""
WORD_START = "\u2581"  # SentencePiece's word marker


def weights_dir() -> Path:
    """The folder of base-en inside the installed moonshine-cpp wheel, found without importing it."""
    spec = importlib.util.find_spec("moonshine_cpp")  # finds the package; does not run its __init__
    if spec is None or not spec.submodule_search_locations:
        raise VoiceError(
            f"the local speech-to-text engine needs the Moonshine weights from {WEIGHTS_PACKAGE}: "
            "pip install 'rosaos[voice]'"
        )
    folder = Path(next(iter(spec.submodule_search_locations))).joinpath(*MODEL_DIR)
    missing = [
        name
        for name in ("encoder_model.ort", "decoder_model_merged.ort", "tokenizer.bin")
        if not (folder / name).is_file()
    ]
    if missing:
        raise VoiceError(
            f"{folder} lacks {', '.join(missing)}; reinstall {WEIGHTS_PACKAGE} (pip install --force-reinstall)"
        )
    return folder


def read_tokenizer(path: Path) -> list[bytes]:
    """The vocabulary: ``tokenizer.bin`` is each token's bytes, each after a one-byte length."""
    data = path.read_bytes()
    tokens: list[bytes] = []
    offset = 0
    while offset < len(data):
        length = data[offset]
        tokens.append(data[offset + 1 : offset + 1 + length])
        offset += 1 + length
    if offset != len(data) or len(tokens) < 1000:
        raise VoiceError(f"{path} is not a Moonshine tokenizer (read {len(tokens)} tokens)")
    return tokens


def detokenize(tokens: list[bytes], ids: list[int]) -> str:
    """Text from token ids: byte tokens join into UTF-8, the word marker becomes a space."""
    pieces = b"".join(tokens[i] for i in ids if i > EOS and i < len(tokens))
    return pieces.decode("utf-8", errors="replace").replace(WORD_START, " ").strip()


@dataclass(frozen=True)
class _Cache:
    names: list[str]
    """``past_key_values.N.{decoder,encoder}.{key,value}``, in the decoder's input order."""
    heads: int
    head_size: int


_ARENA: list[bool] = []
"""Set once the shared CPU arena is registered with onnxruntime's environment (once a process)."""


def _share_one_arena(ort: Any) -> None:
    """Register one CPU arena for every session of this process, extended only by what is asked."""
    if _ARENA:
        return
    memory = ort.OrtMemoryInfo("Cpu", ort.OrtAllocatorType.ORT_ARENA_ALLOCATOR, 0, ort.OrtMemType.DEFAULT)
    # OrtArenaCfg(max_mem, arena_extend_strategy, initial_chunk_size_bytes, max_dead_bytes_per_chunk):
    # 0 and -1 keep onnxruntime's defaults; strategy 1 is kSameAsRequested.
    ort.create_and_register_allocator(memory, ort.OrtArenaCfg(0, 1, -1, -1))
    _ARENA.append(True)


class MoonshineOnnx:
    """Encoder + merged decoder sessions, and greedy decoding with the key/value cache."""

    def __init__(self, folder: Path | None = None, threads: int = 0) -> None:
        try:
            import onnxruntime as ort
        except ImportError:
            raise VoiceError(
                "the local speech-to-text engine needs onnxruntime: pip install 'rosaos[voice]'"
            ) from None
        folder = folder or weights_dir()
        encoder, decoder = converted([folder / "encoder_model.ort", folder / "decoder_model_merged.ort"])
        options = ort.SessionOptions()
        # The rewrite (onnx_graph) dequantizes each weight just before its product; folding
        # constants would undo it, keeping all 245 MB of float32 weights for good.
        options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
        # Without a memory pattern the arena reuses each buffer once its product is done; with
        # one, onnxruntime plans a block for every buffer of a run at once.
        options.enable_mem_pattern = False
        # Both sessions draw on one process-wide arena that grows by what is asked, not in powers
        # of two: the encoder's buffers serve the decoder afterwards.
        options.add_session_config_entry("session.use_env_allocators", "1")
        _share_one_arena(ort)
        if threads:
            options.intra_op_num_threads = threads
        kept = {"providers": ["CPUExecutionProvider"], "disabled_optimizers": ["ConstantFolding"]}
        self._encoder: Any = ort.InferenceSession(str(encoder), options, **kept)
        self._decoder: Any = ort.InferenceSession(str(decoder), options, **kept)
        self._tokens = read_tokenizer(folder / "tokenizer.bin")
        self._pieces = [
            token.decode("utf-8", errors="ignore").replace(WORD_START, " ").lower() for token in self._tokens
        ]
        self.bias: Bias | None = None
        """Nudges decoding toward this world's words (:mod:`rosaos.frontends.voice.word_bias`)."""
        past = [i for i in self._decoder.get_inputs() if i.name.startswith("past_key_values.")]
        self._cache = _Cache([i.name for i in past], int(past[0].shape[1]), int(past[0].shape[3]))
        self._outputs = [o.name for o in self._decoder.get_outputs()]

    def transcribe(self, samples: Samples) -> str:
        """The transcript of one utterance (mono float32 at 16 kHz). Blocking; call it in a thread."""
        audio = np.ascontiguousarray(samples, dtype=np.float32).reshape(1, -1)
        (hidden,) = self._encoder.run(["last_hidden_state"], {"input_values": audio})
        limit = max(4, int(audio.shape[1] / SAMPLE_RATE * TOKENS_PER_SECOND))
        empty = np.zeros((1, self._cache.heads, 0, self._cache.head_size), dtype=np.float32)
        past = dict.fromkeys(self._cache.names, empty)
        ids: list[int] = []
        token = BOS
        word = ""  # the word being spelled, for the bias
        for step in range(limit):
            feed = {
                "input_ids": np.array([[token]], dtype=np.int64),
                "encoder_hidden_states": hidden,
                "use_cache_branch": np.array([step > 0]),
                **past,
            }
            logits, *present = self._decoder.run(self._outputs, feed)
            bias = self.bias
            token = (
                int(np.argmax(logits[0, -1]))
                if bias is None
                else bias.choose(logits[0, -1], word, self._pieces)
            )
            if token == EOS:
                break
            ids.append(token)
            piece = self._pieces[token] if token < len(self._pieces) else ""
            word = piece.strip() if piece.startswith(" ") else word + piece
            for name, value in zip(self._outputs[1:], present, strict=True):
                key = name.replace("present.", "past_key_values.", 1)
                # The encoder's keys and values are computed on the first step only; on the cached
                # branch the decoder passes back placeholders for them, so keep the first ones.
                if step == 0 or ".decoder." in key:
                    past[key] = value
        text = detokenize(self._tokens, ids)
        return self.bias.correct(text) if self.bias is not None else text
