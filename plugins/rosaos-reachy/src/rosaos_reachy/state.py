"""What the tools return: the device state (``get_state``) and the reports of actions."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from rosaos_reachy.faces import Face

CompanionMode = Literal["breathing", "listening", "speaking", "asleep", "off"]


class HeadState(BaseModel):
    """Head pose relative to the base: mm and degrees (yaw + left, pitch + down, roll + right)."""

    x: float
    y: float
    z: float
    roll: float
    pitch: float
    yaw: float


class ReachyState(BaseModel):
    """``get_state``: the benchmark's keys first, then what else a caller may want to know."""

    head: HeadState
    antennas: list[float] = Field(
        description="[left, right] degrees; equal values are symmetric, ~10 is rest."
    )
    body_yaw: float = Field(description="Body rotation in degrees from facing forward, + to the left.")
    awake: bool
    last_spoken: str = Field(description="The text of the last speak.")
    speaking: bool
    speaking_until: float | None = Field(
        description="Epoch seconds when the current sentence ends; the voice front end ignores the "
        "microphones until then, so the robot does not hear itself."
    )
    moving: str | None = Field(description="The motion under way, e.g. 'emotion happy'; null when still.")
    mode: str = Field(description="'real', or which simulation runs: 'sim: MuJoCo' or 'sim: mockup (...)'.")
    camera: Literal["robot", "simulated", "none"]
    emotions: str = Field(description="Where emotions come from: 'built-in' or 'dataset <name>'.")
    companion: CompanionMode = Field(
        description="What the robot does on its own between motion tools: breathing (idle), listening "
        "(antennas wave), speaking (head sways), asleep, or off (disabled, or after an emergency stop)."
    )
    follow_face: bool = Field(description="While listening or speaking, it keeps facing the face in view.")


class MotionReport(BaseModel):
    """The result of a motion tool: what happened, and the pose afterwards."""

    message: str
    head: HeadState
    antennas: list[float]
    body_yaw: float
    awake: bool
    moving: str | None


class CompanionReport(BaseModel):
    """What ``set_listening`` and ``follow_face`` return."""

    companion: CompanionMode
    follow_face: bool
    listening: bool


class PictureReport(BaseModel):
    """``take_picture``: where the JPEG is, relative to the shared images directory."""

    path: str
    simulated: bool
    width: int
    height: int
    note: str


class FacesReport(BaseModel):
    """``detect_faces``: every face found, largest first."""

    path: str
    count: int
    faces: list[Face]
    remembered: list[str] = Field(description="Names of the faces this robot has been told to remember.")
    note: str
