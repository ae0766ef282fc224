"""How the kernel asks people a confirmation question, and reads their spoken or typed answer."""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Mapping

from rosaos.confirmations.confirmation_desk import Confirmation, ConfirmationDesk
from rosaos.devices.client import DeviceClient
from rosaos.devices.endpoints import DeviceEndpoint
from rosaos.events.types import Event
from rosaos.kernel.activity import ActivityLog
from rosaos.kernel.loop import Output
from rosaos.kernel.updates import UpdateStream
from rosaos.receipts import Receipt, SafetyDecision, SafetyKind

log = logging.getLogger(__name__)
SPEAK_TIMEOUT = 5.0


async def ask_people(
    updates: UpdateStream, endpoints: Mapping[str, DeviceEndpoint], item: Confirmation
) -> None:
    """Ask on the updates stream (chat, web page), and out loud on the always-attached device."""
    await updates.publish("notice", f"confirm {item.id}: {item.question}", item.model_dump(mode="json"))
    speaker = next((e for e in endpoints.values() if e.always_attached and e.url), None)
    if speaker is None or speaker.url is None:
        return
    try:
        async with asyncio.timeout(SPEAK_TIMEOUT):
            await DeviceClient(speaker.url, speaker.token, SPEAK_TIMEOUT, speaker.name).call(
                "speak", {"text": item.question}
            )
    except Exception as failure:  # the chat and the web page still ask; a mute robot is not fatal
        log.warning("could not ask confirmation %s out loud on %s: %s", item.id, speaker.name, failure)


DECISIONS: dict[str, SafetyKind] = {
    "pending": "confirm_asked",
    "yes": "confirmed",
    "no": "declined",
    "expired": "expired",
}


async def record_confirmation(activity: ActivityLog, updates: UpdateStream, item: Confirmation) -> None:
    """A question asked or settled, as a safety decision in the activity log (``rosaos log``);
    an expiry is also a notice, so the people who were asked learn that silence counted as no."""
    decision = SafetyDecision(
        decision=DECISIONS[item.state],
        rule="confirm",
        detail=item.question if item.state == "pending" else f"{item.state} (by {item.answered_by})",
    )
    receipt = Receipt(
        device=item.device,
        tool=item.tool,
        arguments=item.arguments,
        ok=item.state in ("pending", "yes"),
        error=None if item.state in ("pending", "yes") else f"not confirmed: {item.state}",
        started=item.created if item.state == "pending" else time.time(),
        duration=0.0,
        safety=decision,
    )
    try:
        await activity.record(None, item.process_id, [receipt])
        if item.state == "expired":
            text = f"confirm {item.id} expired: nobody answered, so it was not done: {item.question}"
            await updates.publish("notice", text, item.model_dump(mode="json"))
    except Exception as failure:  # the log must not break the question itself
        log.warning("could not log confirmation %s: %s", item.id, failure)


async def answer_from_chat(desk: ConfirmationDesk, event: Event) -> list[Output] | None:
    """A typed or spoken "yes"/"no" while a question is pending answers it, before the model runs."""
    if event.kind not in ("user_said", "user_typed") or not desk.pending():
        return None
    item = desk.answer_oldest(str(getattr(event.payload, "text", "")), by=event.source)
    if item is None:
        return None
    verdict = "going ahead" if item.state == "yes" else "cancelled"
    what = item.question.removesuffix(" Go ahead?")
    return [("kernel_reply", f"{verdict}: {what}", item.model_dump(mode="json"))]
