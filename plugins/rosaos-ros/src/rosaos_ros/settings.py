"""One robot's settings: the keys of ``[devices.NAME]`` besides driver, backend and sim.

Named ``rosbridge_port``/``rosbridge_token`` because ``port`` and ``token`` belong to rosaOS
itself (the device server's loopback port and bearer token).
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

from pydantic import Field, SecretStr, field_validator

from rosaos.drivers import DeviceSettings

GlobList = Annotated[list[str], Field(max_length=200)]


class RosSettings(DeviceSettings):
    """How to reach one ROS 2 robot through rosbridge, what it is, and what it may be told to do."""

    host: str = Field(
        default="127.0.0.1", description="Hostname or IP address of the robot's rosbridge server."
    )
    rosbridge_port: Annotated[int, Field(ge=1, le=65535)] = Field(
        default=9090, description="rosbridge's WebSocket port (its launch file's default is 9090)."
    )
    secure: bool = Field(
        default=False, description="Use wss:// (rosbridge behind TLS, e.g. a reverse proxy)."
    )
    rosbridge_token: SecretStr | None = Field(
        default=None,
        description="Sent as 'Authorization: Bearer <token>' when connecting (a proxy in front of rosbridge checks it).",
    )
    profile: str | None = Field(
        default=None,
        description="Robot profile: turtlebot4, puppypi, generic, or a file name in <data_dir>/drivers/ros/profiles. "
        "Default: the sim table's profile, else generic.",
    )
    profile_file: Path | None = Field(
        default=None, description="A profile YAML file of your own; wins over profile."
    )
    namespace: str = Field(default="", description="ROS namespace the robot runs under, e.g. /robot1.")
    max_linear: Annotated[float, Field(gt=0, le=10)] | None = Field(
        default=None,
        description="Velocity limit in m/s; default: the profile's. Commands above it are refused.",
    )
    max_angular: Annotated[float, Field(gt=0, le=20)] | None = Field(
        default=None,
        description="Turn-rate limit in rad/s; default: the profile's. Commands above it are refused.",
    )
    publish_allow: GlobList = Field(
        default_factory=list, description="Topics that may be published, besides the profile's."
    )
    publish_deny: GlobList = Field(default_factory=list, description="Topics that may never be published.")
    service_allow: GlobList = Field(
        default_factory=list, description="Services that may be called, besides the profile's."
    )
    service_deny: GlobList = Field(default_factory=list, description="Services that may never be called.")
    param_allow: GlobList = Field(
        default_factory=list, description="Parameters (/node:param) that may be set or deleted."
    )
    param_deny: GlobList = Field(
        default_factory=list, description="Parameters that may never be set or deleted."
    )
    action_allow: GlobList = Field(
        default_factory=list, description="Actions that may be sent goals, besides the profile's."
    )
    action_deny: GlobList = Field(default_factory=list, description="Actions that may never be sent goals.")
    camera_topic: str | None = Field(
        default=None,
        description="Camera topic for capture_image (Image or CompressedImage); default: the profile's.",
    )
    camera_fov: Annotated[float, Field(ge=20, le=170)] = Field(
        default=70.0,
        description="The camera's horizontal field of view in degrees, for where detect_people places a person "
        "(an OAK-D's colour camera: 69; the simulator's: 70).",
    )
    search_seconds: Annotated[float, Field(ge=5, le=600)] = Field(
        default=120.0,
        description="How long search looks when its call names no max_seconds: a small flat is "
        "searched sooner, a warehouse takes longer.",
    )
    connect_timeout: Annotated[float, Field(gt=0, le=120)] = Field(
        default=5.0, description="Seconds to wait for rosbridge at start before giving up."
    )
    call_timeout: Annotated[float, Field(gt=0, le=120)] = Field(
        default=10.0, description="Seconds one rosbridge request (service call, introspection) may take."
    )

    @field_validator("namespace")
    @classmethod
    def _absolute_namespace(cls, value: str) -> str:
        value = value.strip().strip("/")
        return f"/{value}" if value else ""

    @field_validator("camera_topic")
    @classmethod
    def _absolute_topic(cls, value: str | None) -> str | None:
        if value is not None and not value.startswith("/"):
            raise ValueError(f"camera_topic must be an absolute ROS name like /{value}")
        return value
