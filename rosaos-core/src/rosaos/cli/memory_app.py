"""``rosaos places ...`` and ``rosaos memory ...``: what rosaOS remembers, from the shell.

Both read and change the data directory's ``memory.db`` directly (SQLite in WAL mode), so they
work whether or not the kernel runs, and the kernel sees a change on its next sentence.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from rosaos.cli.console import console as terminal
from rosaos.cli.options import ConfigOption, JsonOption

places_app = typer.Typer(
    help="The named places robots can go to: list, add, rename, delete.", invoke_without_command=True
)
memory_app = typer.Typer(
    help="What people told rosaOS (facts, aliases, preferences) and the places: list, export, forget, clear.",
    no_args_is_help=True,
)
if TYPE_CHECKING:
    from rosaos.memory.sightings import SightingLog
    from rosaos.memory.store import MemoryStore

PlaceArgument = Annotated[str, typer.Argument(help="The place's name, e.g. 'the kitchen'.")]


def _store(config: Path | None) -> MemoryStore:
    from rosaos.config import ConfigError, load_config
    from rosaos.memory.store import MemoryStore

    try:
        return MemoryStore.open(load_config(config).data_dir)
    except ConfigError as error:
        typer.echo(f"error: {error}", err=True)
        raise typer.Exit(2) from None


def _sightings(config: Path | None) -> SightingLog:
    from rosaos.config import load_config
    from rosaos.memory.sightings import SightingLog

    settings = load_config(config)  # _store already said what is wrong with a bad config
    return SightingLog(
        _store(config), settings.memory.sightings_days, images_dir=settings.data_dir / "images"
    )


def _fail(error: Exception) -> typer.Exit:
    typer.echo(f"error: {error}", err=True)
    return typer.Exit(1)


@places_app.callback()
def places_list(ctx: typer.Context, config: ConfigOption = None, json_output: JsonOption = False) -> None:
    """List the named places (the default): name, robot, frame, x, y, yaw."""
    if ctx.invoked_subcommand is not None:
        return
    places = _store(config).places()
    if json_output:
        typer.echo(json.dumps([place.model_dump(mode="json") for place in places], indent=2))
        return
    if not places:
        typer.echo("no places yet: stand a robot somewhere and say 'remember this spot as the kitchen'")
        return
    table = Table("name", "robot", "frame", "x", "y", "yaw", "anchor")
    for place in places:
        yaw = "" if place.yaw is None else f"{place.yaw:.2f}"
        table.add_row(
            place.name, place.device, place.frame, f"{place.x:.2f}", f"{place.y:.2f}", yaw, place.anchor
        )
    terminal().print(table)


@places_app.command("add")
def places_add(
    name: PlaceArgument,
    x: Annotated[float, typer.Option("--x", help="Metres.")],
    y: Annotated[float, typer.Option("--y", help="Metres.")],
    device: Annotated[str, typer.Option("--device", "-d", help="The robot's instance name.")],
    yaw: Annotated[float | None, typer.Option("--yaw", help="Heading in radians.")] = None,
    anchor: Annotated[
        str | None,
        typer.Option(
            "--anchor",
            help="The frame anchor (the robot's get_pose 'anchor', e.g. map:/maps/home.yaml); "
            "default: that of the robot's other places.",
        ),
    ] = None,
    config: ConfigOption = None,
    json_output: JsonOption = False,
) -> None:
    """Add (or replace) a place at given coordinates in a robot's frame."""
    from pydantic import ValidationError

    from rosaos.memory.store import Place

    store = _store(config)
    if anchor is None:
        same = [place for place in store.places() if place.device == device]
        if not same:
            raise _fail(
                ValueError(
                    f"no place of {device} gives its frame yet: pass --anchor (the 'anchor' its get_pose tool "
                    "reports), or save one spot by voice first"
                )
            )
        anchor = same[-1].anchor
    frame = anchor.split(":", 1)[0]
    try:
        place = Place(
            name=name, device=device, frame=frame, anchor=anchor, x=x, y=y, yaw=yaw, saved_at=time.time()
        )
    except ValidationError as error:
        problem = error.errors()[0]
        raise _fail(ValueError(f"{problem['loc'][0]}: {problem['msg']}")) from None
    store.save_place(place)
    typer.echo(json.dumps(place.model_dump(mode="json")) if json_output else f"saved {name} ({frame} frame)")


@places_app.command("rename")
def places_rename(name: PlaceArgument, new_name: PlaceArgument, config: ConfigOption = None) -> None:
    """Rename a place."""
    from rosaos.memory.store import MemoryRequestError

    try:
        place = _store(config).rename_place(name, new_name)
    except MemoryRequestError as error:
        raise _fail(error) from None
    typer.echo(f"renamed {name} to {place.name}")


@places_app.command("delete")
def places_delete(name: PlaceArgument, config: ConfigOption = None) -> None:
    """Delete a place."""
    from rosaos.memory.store import MemoryRequestError

    try:
        place = _store(config).forget_place(name)
    except MemoryRequestError as error:
        raise _fail(error) from None
    typer.echo(f"deleted {place.name}")


@memory_app.command("list")
def memory_list(config: ConfigOption = None, json_output: JsonOption = False) -> None:
    """List what people told rosaOS: kind, key, value, and the sentence."""
    notes = _store(config).notes()
    if json_output:
        typer.echo(json.dumps([note.model_dump(mode="json") for note in notes], indent=2))
        return
    if not notes:
        typer.echo("nothing remembered yet")
        return
    table = Table("kind", "key", "value", "said")
    for note in notes:
        table.add_row(note.kind, note.key, note.value, note.said)
    terminal().print(table)


@memory_app.command("export")
def memory_export(config: ConfigOption = None) -> None:
    """Print everything remembered (notes and places) as one JSON document."""
    store = _store(config)
    document = {
        "notes": [note.model_dump(mode="json") for note in store.notes()],
        "places": [place.model_dump(mode="json") for place in store.places()],
    }
    typer.echo(json.dumps(document, indent=2))


@memory_app.command("forget")
def memory_forget(
    words: Annotated[list[str], typer.Argument(help="Words of what to forget, e.g. my name is Sam.")],
    config: ConfigOption = None,
) -> None:
    """Forget the notes that contain all these words."""
    gone = _store(config).forget_notes(" ".join(words))
    if not gone:
        raise _fail(
            ValueError(f"nothing remembered matches {' '.join(words)!r}; `rosaos memory list` shows it all")
        )
    for note in gone:
        typer.echo(f"forgot: {note.said}")


@memory_app.command("sightings")
def memory_sightings(config: ConfigOption = None, json_output: JsonOption = False) -> None:
    """List what the robots saw, newest first: id, what, when, robot, nearest place, picture file."""
    from rosaos.memory.sightings import ago

    log = _sightings(config)
    seen = log.recent(limit=500)
    if json_output:
        rows = [s.model_dump(mode="json") | {"picture_file": _file(log.picture(s))} for s in seen]
        typer.echo(json.dumps(rows, indent=2))
        return
    if not seen:
        typer.echo(f"nothing seen in the last {log.keep_days:g} days")
        return
    table = Table("id", "what", "when", "robot", "place", "picture")
    for s in seen:
        table.add_row(str(s.id), s.what, ago(s.at), s.device, s.place or "", _file(log.picture(s)) or "")
    terminal().print(table)


@memory_app.command("picture")
def memory_picture(
    sighting_id: Annotated[
        int | None, typer.Argument(help="The sighting's id (`rosaos memory sightings`); default: the newest.")
    ] = None,
    config: ConfigOption = None,
) -> None:
    """Print the file path of a sighting's picture ("show me", from the shell)."""
    log = _sightings(config)
    found = log.get(sighting_id) if sighting_id is not None else log.with_picture()
    if found is None:
        which = f"sighting {sighting_id}" if sighting_id is not None else "sighting with a picture"
        raise _fail(
            ValueError(f"no {which} in the last {log.keep_days:g} days; `rosaos memory sightings` lists them")
        )
    path = log.picture(found)
    if path is None:
        raise _fail(
            ValueError(
                f"sighting {found.id} has no picture on this machine (none was taken, or it was deleted)"
            )
        )
    typer.echo(str(path.resolve()))


def _file(path: Path | None) -> str | None:
    return str(path.resolve()) if path is not None else None


@memory_app.command("clear")
def memory_clear(
    yes: Annotated[bool, typer.Option("--yes", help="Do not ask.")] = False, config: ConfigOption = None
) -> None:
    """Forget everything: every note and every place."""
    if not yes and not typer.confirm("Forget every place and everything people told rosaOS?"):
        raise typer.Exit(1)
    places, notes = _store(config).clear()
    typer.echo(f"forgot {notes} notes and {places} places")
