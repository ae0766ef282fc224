"""ROS interface structures for a model: rosapi's flat ``TypeDef`` lists turned into nested fields.

rosapi answers ``message_details`` with one typedef per type (the asked-for type first, then every
nested type). A model needs the tree instead: each field's type, nested fields spelled out, array
sizes, constants, and an example message it can copy and fill in.
"""

from __future__ import annotations

from typing import Any

from rosaos_ros.messages import normalize_type

MAX_DEPTH = 12
"""ROS messages do not nest recursively, but a broken typedef list must not loop forever."""

_NUMBERS = {"float32", "float64"}
_INTEGERS = {"byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"}


def structure(typedefs: list[dict[str, Any]]) -> dict[str, Any]:
    """The nested description of the first typedef's type.

    ``fields`` maps each field name to its type: a primitive as a string (``"float64"``,
    ``"float64[36]"``, ``"uint8[]"``), a nested message as ``{"type": ..., "fields": {...}}``
    (``"array"`` gives ``"unbounded"`` or a length when it is an array). ``example`` is a valid
    message with the default values; ``constants`` appears when the type defines any.
    """
    by_type = {normalize_type(str(typedef.get("type", ""))): typedef for typedef in typedefs}
    root = normalize_type(str(typedefs[0].get("type", "")))
    fields, example, constants = _expand(root, by_type, 0)
    described: dict[str, Any] = {"type": root, "fields": fields, "example": example}
    if constants:
        described["constants"] = constants
    return described


def _expand(
    type_name: str, by_type: dict[str, dict[str, Any]], depth: int
) -> tuple[dict[str, Any], dict[str, Any], dict[str, str]]:
    typedef = by_type.get(type_name)
    if typedef is None or depth > MAX_DEPTH:
        return {}, {}, {}
    fields: dict[str, Any] = {}
    example: dict[str, Any] = {}
    names = typedef.get("fieldnames") or []
    types = typedef.get("fieldtypes") or []
    lengths = typedef.get("fieldarraylen") or [-1] * len(names)
    examples = typedef.get("examples") or [""] * len(names)
    for name, field_type, length, sample in zip(names, types, lengths, examples, strict=False):
        nested = normalize_type(field_type) if normalize_type(field_type) in by_type else None
        suffix = "" if length < 0 else "[]" if length == 0 else f"[{length}]"
        if nested is None:
            fields[name] = f"{field_type}{suffix}"
            value: Any = _primitive(field_type, str(sample))
        else:
            sub_fields, sub_example, sub_constants = _expand(nested, by_type, depth + 1)
            fields[name] = {"type": nested, "fields": sub_fields}
            if length >= 0:
                fields[name]["array"] = "unbounded" if length == 0 else length
            if sub_constants:
                fields[name]["constants"] = sub_constants
            value = sub_example
        if length > 0:
            example[name] = [value] * length
        elif length == 0:
            example[name] = []
        else:
            example[name] = value
    constants = dict(zip(typedef.get("constnames") or [], typedef.get("constvalues") or [], strict=False))
    return fields, example, constants


def _primitive(field_type: str, sample: str) -> Any:
    """The example value of a primitive field, typed as it travels in rosbridge JSON."""
    if field_type == "bool":
        return sample.strip().lower() == "true"
    if field_type in _NUMBERS:
        try:
            return float(sample)
        except ValueError:
            return 0.0
    if field_type in _INTEGERS:
        try:
            return int(sample)
        except ValueError:
            return 0
    return sample if field_type in ("string", "wstring") else sample or None
