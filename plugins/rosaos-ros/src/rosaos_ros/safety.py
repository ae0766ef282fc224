"""The safety rules, enforced in the driver whatever the model asks: access lists and velocity limits.

- :class:`AccessPolicy`: glob allow-lists and deny-lists for publishing to topics, calling
  services, setting parameters and sending action goals. A name must match an allow glob and
  no deny glob; the default (a profile's lists) denies everything the robot does not need.
- :class:`VelocityLimits`: commands faster than the limit are refused, not silently clamped, so
  the model learns the limit instead of believing it went at the speed it asked for.

Every refusal is a :class:`Refused` whose message names the rule and the setting that changes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from fnmatch import fnmatchcase
from typing import Literal

from rosaos.drivers import DeviceError
from rosaos_ros.profiles import Profile
from rosaos_ros.settings import RosSettings

Kind = Literal["publish", "services", "params", "actions"]
KINDS: tuple[Kind, ...] = ("publish", "services", "params", "actions")
SETTING_PREFIX: dict[Kind, str] = {
    "publish": "publish",
    "services": "service",
    "params": "param",
    "actions": "action",
}
DOING: dict[Kind, str] = {
    "publish": "publishing to topic",
    "services": "calling service",
    "params": "changing parameter",
    "actions": "sending a goal to action",
}

# Ways around the parameter rules: never callable through call_service, whatever the lists say.
ALWAYS_DENIED_SERVICES = {
    "/rosapi/set_param": "use set_param, which checks the parameter allow-list",
    "/rosapi/delete_param": "use delete_param, which checks the parameter allow-list",
    "*/set_parameters": "use set_param, which checks the parameter allow-list",
    "*/set_parameters_atomically": "use set_param, which checks the parameter allow-list",
}


class Refused(DeviceError):
    """A command a safety rule refused. The message says which rule, and how to change it in config."""


@dataclass(frozen=True)
class Rule:
    """One glob and where it came from (for the refusal message)."""

    glob: str
    source: str


@dataclass(frozen=True)
class AccessPolicy:
    """Who may publish, call, set and send what, on one instance."""

    instance: str
    profile: str
    allow: dict[Kind, tuple[Rule, ...]]
    deny: dict[Kind, tuple[Rule, ...]]

    @classmethod
    def build(cls, instance: str, profile: Profile, settings: RosSettings) -> AccessPolicy:
        """The profile's lists, extended by the instance's ``*_allow``/``*_deny`` settings."""
        where = f"[devices.{instance}]"
        allow: dict[Kind, tuple[Rule, ...]] = {}
        deny: dict[Kind, tuple[Rule, ...]] = {}
        for kind in KINDS:
            prefix = SETTING_PREFIX[kind]
            allow[kind] = tuple(
                [Rule(g, f"profile {profile.name}") for g in getattr(profile.allow, kind)]
                + [Rule(g, f"{where} {prefix}_allow") for g in getattr(settings, f"{prefix}_allow")]
            )
            deny[kind] = tuple(
                [Rule(g, f"profile {profile.name}") for g in getattr(profile.deny, kind)]
                + [Rule(g, f"{where} {prefix}_deny") for g in getattr(settings, f"{prefix}_deny")]
            )
        return cls(instance, profile.name, allow, deny)

    def check(self, kind: Kind, name: str, hint: str = "") -> None:
        """Raise :class:`Refused` unless ``name`` may be used for ``kind``; ``hint`` adds advice."""
        setting = f"{SETTING_PREFIX[kind]}_allow"
        where = f"[devices.{self.instance}]"
        if kind == "services":
            for glob, instead in ALWAYS_DENIED_SERVICES.items():
                if fnmatchcase(name, glob):
                    raise Refused(
                        f"refused: calling service {name} is never allowed through call_service; {instead}"
                    )
        for rule in self.deny[kind]:
            if fnmatchcase(name, rule.glob):
                raise Refused(
                    f"refused: {DOING[kind]} {name} is denied by the rule {rule.glob!r} ({rule.source}). "
                    f"To allow it, remove that glob from {rule.source.removeprefix('profile ')}"
                    + (" (in a copy of the profile)" if rule.source.startswith("profile") else "")
                    + (f". {hint}" if hint else "")
                )
        if any(fnmatchcase(name, rule.glob) for rule in self.allow[kind]):
            return
        allowed = ", ".join(rule.glob for rule in self.allow[kind]) or "nothing"
        raise Refused(
            f"refused: {DOING[kind]} {name} is not in the allow-list (allowed: {allowed}); by default the "
            f"driver denies what the {self.profile} profile does not need. "
            + (f"{hint} " if hint else "")
            + f'To allow it, add it to {setting} in {where}, e.g. {setting} = ["{name}"]'
        )

    def allowed(self, kind: Kind) -> list[str]:
        """The allow globs of ``kind``, for the device prompt and ``get_state`` readers."""
        return [rule.glob for rule in self.allow[kind]]


@dataclass(frozen=True)
class VelocityLimits:
    """The largest speeds this instance may command."""

    instance: str
    linear: float
    angular: float
    linear_source: str
    angular_source: str

    @classmethod
    def build(cls, instance: str, profile: Profile, settings: RosSettings) -> VelocityLimits:
        """The profile's limits unless the instance sets ``max_linear``/``max_angular``."""
        where = f"[devices.{instance}]"
        return cls(
            instance,
            settings.max_linear or profile.limits.linear,
            settings.max_angular or profile.limits.angular,
            f"{where} max_linear" if settings.max_linear else f"profile {profile.name}",
            f"{where} max_angular" if settings.max_angular else f"profile {profile.name}",
        )

    def check(self, linear: float, angular: float) -> None:
        """Raise :class:`Refused` when either speed is above its limit (either direction)."""
        where = f"[devices.{self.instance}]"
        if abs(linear) > self.linear + 1e-9:
            raise Refused(
                f"refused: {abs(linear):g} m/s is above the velocity limit of {self.linear:g} m/s "
                f"({self.linear_source}); ask for {self.linear:g} m/s or less, or raise max_linear in {where} "
                "if the robot and its surroundings can take it"
            )
        if abs(angular) > self.angular + 1e-9:
            raise Refused(
                f"refused: {abs(angular):g} rad/s is above the turn-rate limit of {self.angular:g} rad/s "
                f"({self.angular_source}); ask for {self.angular:g} rad/s or less, or raise max_angular in {where} "
                "if the robot and its surroundings can take it"
            )
