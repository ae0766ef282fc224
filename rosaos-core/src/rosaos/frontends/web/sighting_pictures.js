// "Show me": a kernel reply that names a sighting's picture (/sightings/{id}/picture, from the
// show_sighting tool) gets that picture under it. The picture needs the token like every
// protected route, so it is fetched with api() and shown from a blob URL, never linked bare.

import { api, errorText, SignedOut } from "./session.js";

const PICTURE = /\/sightings\/(\d+)\/picture/;

/** Add the picture a kernel reply names under it; a reply that names none is left alone. */
export async function showSightingPicture(item, text) {
  const found = PICTURE.exec(text || "");
  if (!found) return;
  const id = found[1];
  const figure = document.createElement("figure");
  figure.className = "sighting-picture";
  figure.dataset.sighting = id;
  const caption = document.createElement("figcaption");
  caption.textContent = "Loading the picture…";
  figure.append(caption);
  item.append(figure);
  try {
    const response = await api(`/sightings/${id}/picture`);
    if (!response.ok) {
      caption.textContent = `No picture: ${await errorText(response)}`;
      return;
    }
    const image = document.createElement("img");
    image.alt = `The picture of sighting ${id}`;
    image.src = URL.createObjectURL(await response.blob());
    await image.decode().catch(() => { /* shown anyway; the caption says what it is */ });
    figure.prepend(image);
    caption.textContent = `Sighting ${id}`;
  } catch (error) {
    if (!(error instanceof SignedOut)) caption.textContent = "The picture could not be loaded: the kernel cannot be reached.";
  }
}
