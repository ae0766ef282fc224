#!/usr/bin/env bash
# Take a fresh Debian machine (or a dev box) to a ready .venv with every rosaOS package installed.
# Sourced by scripts/up and scripts/test, so either README command works on a fresh clone.
# Idempotent and quick when nothing changed: a stamp of the inputs skips the install step.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
UV_VERSION="0.13.9"

say() { printf '\033[1;34m[rosaos setup]\033[0m %s\n' "$*" >&2; }

# Debian packages: the interpreter, and what tests and drivers use at run time.
#   python3-venv     the venv this script creates
#   git              copier (rosaos new-driver) and the template test
#   chromium         the web page's end-to-end test (Playwright drives the Debian build; no browser download)
#   espeak-ng, sox   offline text-to-speech and the voice tests
#   libportaudio2    the host microphone for `rosaos voice --source mic` (sounddevice)
#   libcairo2-dev, libgirepository1.0-dev, pkg-config
#                    build PyGObject (reachy-mini pins pygobject<=3.46, which builds from source)
#   gir1.2-gstreamer-1.0, gir1.2-gst-plugins-base-1.0
#                    GStreamer typelibs (Gst, GstApp, GstPbutils) the reachy-mini SDK imports at start
#   libegl1, libgl1, libosmesa6
#                    OpenGL/EGL/OSMesa for MuJoCo, the Reachy Mini daemon's headless simulator
APT_PACKAGES=(python3 python3-venv python3-dev gcc git chromium espeak-ng sox libportaudio2
  libcairo2-dev libgirepository1.0-dev pkg-config gir1.2-gstreamer-1.0 gir1.2-gst-plugins-base-1.0
  libegl1 libgl1 libosmesa6)

missing_apt() {
  local pkg missing=()
  for pkg in "${APT_PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  echo "${missing[@]:-}"
}

install_apt() {
  command -v dpkg-query >/dev/null 2>&1 || { say "not a Debian system: install ${APT_PACKAGES[*]} yourself"; return 0; }
  local missing; missing="$(missing_apt)"
  [ -z "$missing" ] && return 0
  local sudo=""
  if [ "$(id -u)" != 0 ]; then
    command -v sudo >/dev/null 2>&1 || { say "missing Debian packages: $missing (run as root or install sudo)"; exit 1; }
    sudo="sudo"
  fi
  say "installing Debian packages: $missing"
  $sudo apt-get update -qq
  # shellcheck disable=SC2086
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends $missing >/dev/null
}

pick_python() {
  # Prefer an interpreter on PATH that is >= 3.11 (pyenv shims, Debian 12's python3.11, ...).
  local candidate
  for candidate in python3.13 python3.12 python3.11 python3; do
    if command -v "$candidate" >/dev/null 2>&1 && \
       "$candidate" -c 'import sys, venv; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
      command -v "$candidate"; return 0
    fi
  done
  say "rosaOS needs Python >= 3.11 with the venv module"; exit 1
}

stamp_inputs() {
  shopt -s nullglob
  cat "$ROOT/constraints.txt" "$ROOT/scripts/bootstrap.sh" "$ROOT/pyproject.toml" \
      "$ROOT"/rosaos-core/pyproject.toml "$ROOT"/plugins/*/pyproject.toml | sha256sum | cut -d' ' -f1
}

install_python_packages() {
  if [ ! -x "$VENV/bin/python" ]; then
    say "creating $VENV"
    "$(pick_python)" -m venv "$VENV"
  fi
  if [ ! -x "$VENV/bin/uv" ] || [ "$("$VENV/bin/uv" --version | cut -d' ' -f2)" != "$UV_VERSION" ]; then
    say "installing uv $UV_VERSION into the venv"
    "$VENV/bin/python" -m pip install -q --disable-pip-version-check "uv==$UV_VERSION"
  fi
  local want; want="$(stamp_inputs)"
  if [ -f "$VENV/.bootstrap-stamp" ] && [ "$(cat "$VENV/.bootstrap-stamp")" = "$want" ]; then
    return 0
  fi
  say "installing rosaOS and its plugins (editable) with pins from constraints.txt"
  local editables=(-e "$ROOT/rosaos-core[testing,voice]")
  local plugin
  shopt -s nullglob
  for plugin in "$ROOT"/plugins/*/; do editables+=(-e "$plugin"); done
  local install=("$VENV/bin/uv" pip install --quiet --python "$VENV/bin/python"
    -c "$ROOT/constraints.txt" "${editables[@]}" --group "$ROOT/pyproject.toml:dev")
  # From uv's cache alone first: every package is pinned in constraints.txt, so on a machine that
  # installed these pins before this is the same set, without asking the index about each one. An
  # online install revalidates every file, and where the index answers "modified" (this CI
  # machine's mirror does) uv builds PyGObject from source again: about 55 s, 10 s from the cache.
  # Anything not cached yet (a fresh machine, a new pin) makes it fail, and the online install runs.
  if ! VIRTUAL_ENV="$VENV" "${install[@]}" --offline 2>/dev/null; then
    VIRTUAL_ENV="$VENV" "${install[@]}"
  fi
  # Write .pyc files now (up-to-date ones are skipped). Where PYTHONDONTWRITEBYTECODE is set, every
  # worker and device host would otherwise recompile fastmcp and pydantic-ai: ~5 s a start, not ~1 s.
  say "compiling bytecode"
  "$VENV/bin/python" -m compileall -q -j 0 "$VENV/lib" "$ROOT/rosaos-core/src" "$ROOT"/plugins/*/src >/dev/null || true
  echo "$want" > "$VENV/.bootstrap-stamp"
}

install_apt
install_python_packages
export PATH="$VENV/bin:$PATH"
