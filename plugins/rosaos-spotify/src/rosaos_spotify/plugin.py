"""The ``spotify`` driver: what it declares to rosaOS, and how its backends are built.

Registered under the ``rosaos.drivers`` entry point as ``spotify`` (see ``pyproject.toml``).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rosaos import hookimpl
from rosaos.card_controls import button, slider, toggle
from rosaos.cards import Card, flag, gauge, text
from rosaos.drivers import DemoInstance, DeviceContext, DeviceError, DriverSpec, read_packaged_text
from rosaos_spotify.backend import SpotifyBackend
from rosaos_spotify.ending import NOTICES
from rosaos_spotify.server import build_server
from rosaos_spotify.settings import SpotifySettings
from rosaos_spotify.simulator import SimBackend, SimSettings

Context = DeviceContext[SpotifySettings]


def real_backend(ctx: Context) -> SpotifyBackend:
    """The ``real`` backend: the owner's Spotify account, logged in with ``rosaos devices login``."""
    # spotipy and requests only where a real instance is served or logged in, not in the kernel.
    from rosaos_spotify.login import DASHBOARD
    from rosaos_spotify.web_api import build_web_backend

    settings = ctx.settings
    if not settings.client_id:
        raise DeviceError(
            f"[devices.{ctx.instance}] needs client_id for the real backend: create an app at {DASHBOARD} "
            f"with Redirect URI {settings.redirect_uri}, copy its Client ID there, then run "
            f"`rosaos devices login {ctx.instance}`"
        )
    backend = build_web_backend(ctx.instance, settings, ctx.data_dir)
    backend.ending.notify = ctx.notify
    return backend


def sim_backend(ctx: Context) -> SpotifyBackend:
    """The ``sim`` backend: an in-process player starting in the state ``ctx.sim`` gives."""
    backend = SimBackend(ctx.instance, SimSettings.from_sim(ctx.instance, dict(ctx.sim)))
    backend.ending.notify = ctx.notify
    return backend


def login(ctx: Context) -> int:
    """``rosaos devices login NAME``: log the instance in to Spotify by copy and paste."""
    from rosaos_spotify.login import login_interactive

    return login_interactive(ctx.settings, ctx.data_dir, ctx.instance)


async def pause_music(backend: SpotifyBackend) -> None:
    """Emergency stop: pause the music, so people can hear each other (and the robot)."""
    await backend.pause()


SPEC: DriverSpec[SpotifyBackend, SpotifySettings] = DriverSpec(
    name="spotify",
    title="Spotify playback",
    description=(
        "Music from Spotify on a speaker: play a song, an artist, an album or a genre, pause, "
        "resume, skip forward or back, set or change the volume, shuffle, repeat, queue a song, "
        "search for music, and read what is playing."
    ),
    concurrency="exclusive",
    prompt=read_packaged_text(__file__, "prompt.md"),
    settings=SpotifySettings,
    server=build_server,
    backends={"sim": sim_backend, "real": real_backend},
    intents=Path(__file__).parent / "intents.yaml",
    safe_stop=pause_music,
    halts=("sound",),
    notices=NOTICES,
    card=Card.of(
        text("track", label="Track"),
        text("artist", label="Artist"),
        flag("is_playing", label="State", on_text="playing", off_text="paused"),
        gauge("volume", label="Volume", unit="%"),
        flag("shuffle", label="Shuffle", on_text="on", off_text="off"),
        text("repeat", label="Repeat"),
        controls=[
            toggle("Play", on_tool="resume", off_tool="pause", key="is_playing"),
            button("Next", "next_track"),
            slider("Volume", tool="set_volume", argument="volume", key="volume", unit="%"),
        ],
        noun="speaker",
    ),
    demo={
        "spotify": DemoInstance(
            description="Music on the living room speaker", sim={"is_playing": False, "volume": 40}
        )
    },
    login=login,
)


@hookimpl
def register_drivers(register: Callable[[DriverSpec], None]) -> None:
    """Register the ``spotify`` driver."""
    register(SPEC)
