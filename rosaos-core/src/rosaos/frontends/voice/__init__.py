"""``rosaos voice``: the voice front end. Audio in, transcripts to the kernel's ``POST /stt``.

One module per role, in the order audio flows through them:

- ``sources``: where audio (and camera frames) come from: a WAV file, the host microphone, the
  Reachy Mini's microphone array.
- ``vad``: voice activity detection cuts the stream into utterances (:class:`SpeechSegment`).
- ``stt``: speech-to-text engines: Moonshine offline, Groq, any OpenAI-compatible endpoint.
- ``early``: early transcription: start STT on the VAD's draft while it waits out the silence.
- ``bargein``: the user talks over the robot; an echo gate keeps the robot's own voice out.
- ``wake``: the wake phrase, the follow-up window and eye contact decide what is a command.
- ``robot``: the Reachy Mini's side: turn and wave on wake, speak, and know when it is speaking.
- ``replies``: follows the kernel's updates and has the robot say the replies to what it heard.
- ``pipeline``: wires them together and hands each command to the kernel.
- ``command``: the CLI entry point.

Needs the ``voice`` extra (``pip install 'rosaos[voice]'``); the core never imports this package.
"""
