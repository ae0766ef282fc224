"""A standing person, as the simulated camera shows one: drawn once at high resolution, then scaled.

The figure is an adult seen from the front, 1.7 m tall, with the proportions a pedestrian
detector is trained on (head about an eighth of the height, shoulders a quarter of it wide, arms
along the body, two legs). It is drawn with anti-aliased edges on a transparent sprite, so a far
person is a smooth downscale, as a real lens would blur one, not a blocky drawing.
"""

from __future__ import annotations

from functools import cache

from PIL import Image, ImageDraw

PERSON_HEIGHT = 1.7
"""Metres: the simulated person's height."""
PERSON_WIDTH = 0.5
"""Metres across the shoulders and arms (the sprite's width is this over the height)."""
_SPRITE_HEIGHT = 680  # pixels; 4 px a centimetre, so a scaled-down figure keeps its details
_SUPERSAMPLE = 3  # drawn this much larger, then reduced: anti-aliased edges

SKIN = (224, 172, 140, 255)
HAIR = (62, 42, 30, 255)
SHIRT = (196, 64, 52, 255)
TROUSERS = (42, 52, 92, 255)
SHOES = (30, 30, 32, 255)
FEATURES = (70, 45, 40, 255)


@cache
def person_sprite() -> Image.Image:
    """The person as an RGBA image, transparent around the figure, feet at the bottom row."""
    height = _SPRITE_HEIGHT * _SUPERSAMPLE
    width = round(height * PERSON_WIDTH / PERSON_HEIGHT)
    sprite = Image.new("RGBA", (width, height), (0, 0, 0, 0))
    draw = ImageDraw.Draw(sprite)
    u = height / 100  # the figure is 100 units tall
    cx = width / 2

    def box(a: float, b: float, top: float, bottom: float) -> tuple[float, float, float, float]:
        """Units across (either order) and down, as a pixel box."""
        return (cx + min(a, b) * u, top * u, cx + max(a, b) * u, bottom * u)

    for side in (-1, 1):  # legs, slightly apart, narrowing to the ankles; shoes
        inner, outer = side * 1.0, side * 9.0
        draw.polygon(
            [
                (cx + inner * u, 52 * u),
                (cx + outer * u, 52 * u),
                (cx + side * 8 * u, 96 * u),
                (cx + side * 2 * u, 96 * u),
            ],
            fill=TROUSERS,
        )
        draw.ellipse(box(side * 1.0, side * 10.0, 94, 100), fill=SHOES)
    draw.rounded_rectangle(box(-12, 12, 17, 55), radius=5 * u, fill=SHIRT)  # torso
    for side in (-1, 1):  # arms along the body, hands at the hips
        draw.polygon(
            [
                (cx + side * 12 * u, 19 * u),
                (cx + side * 16 * u, 21 * u),
                (cx + side * 18 * u, 52 * u),
                (cx + side * 13 * u, 52 * u),
                (cx + side * 11 * u, 26 * u),
            ],
            fill=SHIRT,
        )
        draw.ellipse(box(side * 12.5, side * 18.5, 50, 57), fill=SKIN)
    draw.rectangle(box(-3, 3, 12, 18), fill=SKIN)  # neck
    draw.ellipse(box(-6.5, 6.5, 0, 15), fill=SKIN)  # head
    draw.chord(box(-6.8, 6.8, -0.5, 10), 180, 360, fill=HAIR)
    for side in (-1, 1):  # eyes and brows: what a face detector looks for up close
        draw.ellipse(box(side * 1.6, side * 3.8, 6.6, 8.0), fill=FEATURES)
        draw.line(
            [(cx + side * 1.4 * u, 5.6 * u), (cx + side * 4.2 * u, 5.4 * u)], fill=HAIR, width=round(0.5 * u)
        )
    draw.line([(cx - 2 * u, 11.6 * u), (cx + 2 * u, 11.6 * u)], fill=FEATURES, width=round(0.5 * u))  # mouth
    return sprite.resize((width // _SUPERSAMPLE, _SPRITE_HEIGHT), Image.Resampling.LANCZOS)


def person_image(height_px: int) -> Image.Image:
    """The person scaled to ``height_px`` pixels tall (at least 2), RGBA."""
    sprite = person_sprite()
    height = max(2, height_px)
    width = max(1, round(sprite.width * height / sprite.height))
    return sprite.resize((width, height), Image.Resampling.LANCZOS)
