// A light's colour as a CSS colour and as words, from what a bulb reports: on, brightness (%),
// hue (degrees) and saturation (%) in colour mode, or a white colour temperature in kelvin.

const HUES = [
  [15, "red"], [40, "orange"], [70, "yellow"], [160, "green"], [195, "cyan"],
  [255, "blue"], [290, "purple"], [345, "pink"], [361, "red"],
];

/** The name of a colour: "warm white", "pale blue", "red"… */
export function colourName({ hue = 0, saturation = 0, colorTemp = 0 }) {
  if (colorTemp > 0) {
    if (colorTemp < 3300) return "warm white";
    if (colorTemp < 5000) return "neutral white";
    return "cool white";
  }
  if (saturation < 12) return "white";
  const name = HUES.find(([limit]) => hue < limit)[1];
  return saturation < 45 ? `pale ${name}` : name;
}

function hsvToRgb(h, s, v) {
  const f = (n) => {
    const k = (n + h / 60) % 6;
    return v - v * s * Math.max(0, Math.min(k, 4 - k, 1));
  };
  return [f(5), f(3), f(1)].map((c) => Math.round(c * 255));
}

// An approximation of a black body's colour, good enough for 2000-9000 K bulbs.
function kelvinToRgb(kelvin) {
  const t = kelvin / 100;
  const red = t <= 66 ? 255 : 329.7 * (t - 60) ** -0.1332;
  const green = t <= 66 ? 99.47 * Math.log(t) - 161.12 : 288.12 * (t - 60) ** -0.0755;
  const blue = t >= 66 ? 255 : t <= 19 ? 0 : 138.52 * Math.log(t - 10) - 305.04;
  return [red, green, blue].map((c) => Math.round(Math.max(0, Math.min(255, c))));
}

/** The colour a swatch shows: the light's colour dimmed by its brightness; dark grey when off. */
export function swatchColour({ on, brightness = 100, hue = 0, saturation = 0, colorTemp = 0 }) {
  if (!on) return "rgb(60, 60, 60)";
  // Dimmed, not darkened to brown: the text says the exact brightness.
  const level = 0.5 + 0.5 * Math.max(0, Math.min(100, brightness)) / 100;
  const rgb = colorTemp > 0 ? kelvinToRgb(colorTemp) : hsvToRgb(hue, saturation / 100, 1);
  const [r, g, b] = rgb.map((c) => Math.round(c * level));
  return `rgb(${r}, ${g}, ${b})`;
}
