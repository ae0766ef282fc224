"""Controls on a device card: buttons, a toggle, sliders, a choice and a text box, each a tool call.

A driver declares them next to its card's widgets (``Card.of(swatch(), controls=[...])``). A
person pressing one does not call the device directly: the kernel launches a process whose plan is
that one call (:mod:`rosaos.kernel.api.control_routes`), so the call is leased like any other,
refused while the emergency stop is latched, logged in ``rosaos log`` and shown in the page's
Activity. Controls (build them with the functions below)::

    toggle("Power", on_tool="turn_on", off_tool="turn_off", key="on")
    slider("Brightness", tool="set_brightness", argument="brightness", key="brightness", min=1, max=100)
    choice("Colour", tool="set_color_name", argument="name", options=["warm white", "red", "green"])
    button("Next", tool="next_track")
    button("Dock", tool="dock", shown_when={"docked": False})
    button("Stop", tool="stop", preempts=True)   # first stops the process driving the robot
    prompt("Say", tool="speak", argument="text", placeholder="Hello!")

``shown_when`` hides a control unless the state has those values (a missing key hides it too):
a robot without a dock never shows "Dock". The conformance kit checks each control's calls
(:meth:`CardControl.example_calls`) against the tools the driver's server lists.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

ControlKind = Literal["button", "toggle", "slider", "choice", "prompt"]
MAX_TEXT = 500
"""The longest text a ``prompt`` control sends."""


class ControlValueError(ValueError):
    """A value a control cannot send (out of range, not an option); the message says what fits."""


class CardControl(BaseModel):
    """One control on a card, and the tool call it makes."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    kind: ControlKind
    label: str = Field(min_length=1, max_length=40)
    tool: str = Field(min_length=1, description="The tool it calls (a toggle: when switching on).")
    args: dict[str, Any] = Field(default_factory=dict, description="Fixed arguments of every call.")
    off_tool: str | None = Field(default=None, description="A toggle's tool when switching off.")
    key: str | None = Field(default=None, description="The state key that shows the current value.")
    argument: str | None = Field(default=None, description="The argument a person's value fills.")
    min: float = 0.0
    max: float = 100.0
    step: float = 1.0
    unit: str = Field(default="", max_length=12)
    options: list[str] = Field(default_factory=list, max_length=40)
    placeholder: str = Field(default="", max_length=80)
    shown_when: dict[str, Any] = Field(default_factory=dict)
    preempts: bool = False
    """Stop the processes holding the device first ("Stop" on a robot that is searching):
    a person's stop must not wait behind the very task it is meant to stop."""

    @model_validator(mode="after")
    def _check(self) -> CardControl:
        if self.kind == "toggle" and not (self.off_tool and self.key):
            raise ValueError(f"toggle {self.label!r} needs off_tool=<tool> and key=<state key>")
        if self.kind in ("slider", "choice", "prompt") and not self.argument:
            raise ValueError(f"{self.kind} {self.label!r} needs argument=<the tool's argument to fill>")
        if self.kind == "slider" and (self.max <= self.min or self.step <= 0):
            raise ValueError(f"slider {self.label!r}: max must be above min and step above 0")
        if self.kind == "choice" and not self.options:
            raise ValueError(f"choice {self.label!r} needs options=[...]")
        return self

    def call(self, value: Any = None) -> tuple[str, dict[str, Any]]:
        """The tool and arguments for a person's ``value``; :class:`ControlValueError` if it does not fit."""
        if self.kind == "button":
            return self.tool, dict(self.args)
        if self.kind == "toggle":
            if not isinstance(value, bool):
                raise ControlValueError(f"{self.label}: send true (on) or false (off)")
            return (self.tool if value else self.off_tool or self.tool), dict(self.args)
        assert self.argument is not None  # the validator makes sure
        if self.kind == "slider":
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ControlValueError(f"{self.label}: send a number from {self.min:g} to {self.max:g}")
            if not self.min <= value <= self.max:
                raise ControlValueError(f"{self.label}: {value:g} is outside {self.min:g}-{self.max:g}")
            number: float | int = int(value) if float(value).is_integer() else float(value)
            return self.tool, {**self.args, self.argument: number}
        if self.kind == "choice":
            if value not in self.options:
                raise ControlValueError(f"{self.label}: choose one of {', '.join(self.options)}")
            return self.tool, {**self.args, self.argument: value}
        text = value.strip() if isinstance(value, str) else ""
        if not text or len(text) > MAX_TEXT:
            raise ControlValueError(f"{self.label}: type some text (at most {MAX_TEXT} characters)")
        return self.tool, {**self.args, self.argument: text}

    def describe(self, value: Any = None) -> str:
        """What pressing it does, in words, for the process's task ("Power: off")."""
        if self.kind == "button":
            return self.label
        if self.kind == "toggle":
            return f"{self.label}: {'on' if value else 'off'}"
        if self.kind == "prompt":
            return f"{self.label}: “{value}”"
        return f"{self.label}: {value}{f' {self.unit}' if self.unit else ''}"

    def example_calls(self) -> list[tuple[str, dict[str, Any]]]:
        """Every kind of call it can make (a slider at both ends, each option), for the conformance kit."""
        if self.kind == "toggle":
            return [self.call(True), self.call(False)]
        if self.kind == "slider":
            return [self.call(self.min), self.call(self.max)]
        if self.kind == "choice":
            return [self.call(option) for option in self.options]
        if self.kind == "prompt":
            return [self.call("Hello")]
        return [self.call()]


def button(
    label: str,
    tool: str,
    *,
    args: dict[str, Any] | None = None,
    shown_when: dict[str, Any] | None = None,
    preempts: bool = False,
) -> CardControl:
    """A button that makes one call; ``preempts=True`` first stops whatever process holds the device."""
    return CardControl(
        kind="button", label=label, tool=tool, args=args or {}, shown_when=shown_when or {}, preempts=preempts
    )


def toggle(label: str, *, on_tool: str, off_tool: str, key: str) -> CardControl:
    """An on/off switch: ``on_tool`` or ``off_tool``, showing the state's ``key``."""
    return CardControl(kind="toggle", label=label, tool=on_tool, off_tool=off_tool, key=key)


def slider(
    label: str,
    *,
    tool: str,
    argument: str,
    key: str | None = None,
    min: float = 0.0,
    max: float = 100.0,
    step: float = 1.0,
    unit: str = "",
) -> CardControl:
    """A number between ``min`` and ``max``, sent as ``argument`` when a person lets go."""
    return CardControl(
        kind="slider",
        label=label,
        tool=tool,
        argument=argument,
        key=key,
        min=min,
        max=max,
        step=step,
        unit=unit,
    )


def choice(
    label: str, *, tool: str, argument: str, options: list[str], key: str | None = None
) -> CardControl:
    """One of ``options``, sent as ``argument``."""
    return CardControl(kind="choice", label=label, tool=tool, argument=argument, options=options, key=key)


def prompt(label: str, *, tool: str, argument: str, placeholder: str = "") -> CardControl:
    """A text box and a button: the text is sent as ``argument`` ("Say" on a robot that speaks)."""
    return CardControl(kind="prompt", label=label, tool=tool, argument=argument, placeholder=placeholder)
