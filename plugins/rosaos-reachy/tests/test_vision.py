"""Vision: the vision model over the OpenAI chat API (a loopback fake), faces, and the sim camera."""

from __future__ import annotations

import base64
from pathlib import Path

import cv2
import numpy as np
import pytest

from rosaos.drivers import DeviceError
from rosaos_reachy.camera import SimCamera, pixel_to_angles
from rosaos_reachy.faces import FaceDetector, FaceMemory
from rosaos_reachy.robot import HeadPose, Posture
from rosaos_reachy.settings import ReachySettings
from rosaos_reachy.vision import VisionModel, load_image

from .reachy_support import FACE_PHOTO, FakeOpenAI


@pytest.fixture(scope="module")
def photo() -> np.ndarray:
    image = cv2.imread(str(FACE_PHOTO))
    assert image is not None
    return image


@pytest.fixture(scope="module")
def detector() -> FaceDetector:
    return FaceDetector.load()


async def test_describe_image_asks_an_openai_compatible_endpoint(
    photo: np.ndarray, fake_openai: FakeOpenAI
) -> None:
    model = VisionModel(ReachySettings(vision_base_url=fake_openai.url, vision_model="llava"))
    answer = await model.describe(photo, "Who is in the picture?")
    assert answer == fake_openai.answer
    request = fake_openai.requests[-1]
    assert request["path"] == "/v1/chat/completions" and request["body"]["model"] == "llava"
    question, image = request["body"]["messages"][0]["content"]
    assert question == {"type": "text", "text": "Who is in the picture?"}
    url = image["image_url"]["url"]
    assert url.startswith("data:image/jpeg;base64,")
    sent = cv2.imdecode(np.frombuffer(base64.b64decode(url.split(",", 1)[1]), np.uint8), cv2.IMREAD_COLOR)
    assert sent.shape == photo.shape
    assert "Authorization" not in request["headers"]  # a self-hosted endpoint needs no key


async def test_the_default_is_groq_llama_4_scout_with_its_key(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("GROQ_API_KEY", "gsk-test")
    model = VisionModel(ReachySettings())
    assert model.configured and model.key == "gsk-test"
    assert model.base_url == "https://api.groq.com/openai/v1"
    assert model.model == "meta-llama/llama-4-scout-17b-16e-instruct"


async def test_without_a_key_there_is_no_vision_model(photo: np.ndarray) -> None:
    with pytest.raises(DeviceError, match="no vision model configured"):
        await VisionModel(ReachySettings()).describe(photo, "What is this?")


async def test_an_endpoint_error_says_what_to_check(photo: np.ndarray, fake_openai: FakeOpenAI) -> None:
    fake_openai.fail_with = 401
    model = VisionModel(ReachySettings(vision_base_url=fake_openai.url, vision_api_key="bad"))
    with pytest.raises(DeviceError, match=r"HTTP 401.*vision_api_key"):
        await model.describe(photo, "What is this?")
    assert fake_openai.requests[-1]["headers"]["Authorization"] == "Bearer bad"


def test_pictures_are_read_only_from_the_images_directory(tmp_path: Path) -> None:
    (tmp_path / "images").mkdir()
    cv2.imwrite(str(tmp_path / "images" / "a.jpg"), np.zeros((8, 8, 3), np.uint8))
    image, _ = load_image(tmp_path / "images", "a.jpg")
    assert image.shape == (8, 8, 3)
    with pytest.raises(DeviceError, match="outside the images directory"):
        load_image(tmp_path / "images", "../secret.jpg")
    with pytest.raises(DeviceError, match="call take_picture first"):
        load_image(tmp_path / "images", "missing.jpg")


def test_the_haar_cascade_finds_the_face_in_the_photo(photo: np.ndarray, detector: FaceDetector) -> None:
    [(x, y, w, h)] = detector.detect(photo)
    assert 130 < x + w / 2 < 200 and 50 < y + h / 2 < 110  # her face, up and left of centre


def test_a_blank_wall_has_no_face(detector: FaceDetector) -> None:
    assert detector.detect(np.full((480, 640, 3), 180, np.uint8)) == []


def test_face_memory_recognises_the_same_face_and_not_a_stranger(
    photo: np.ndarray, detector: FaceDetector, tmp_path: Path
) -> None:
    memory = FaceMemory(tmp_path / "faces")
    box = detector.detect(photo)[0]
    assert memory.match(photo, box) == (None, None)
    assert memory.remember("Eileen", photo, box) == 1
    shifted = cv2.resize(photo, None, fx=1.3, fy=1.3)  # the same face, nearer the camera
    assert FaceMemory(tmp_path / "faces").match(shifted, detector.detect(shifted)[0])[0] == "Eileen"
    noise = np.random.default_rng(1).integers(0, 255, photo.shape, dtype=np.uint8)
    assert memory.match(noise, box)[0] is None
    with pytest.raises(DeviceError, match="invalid name"):
        memory.remember("../etc", photo, box)
    assert memory.forget("Eileen") and memory.names() == []


def test_the_sim_camera_pans_with_the_head(photo: np.ndarray, detector: FaceDetector) -> None:
    camera = SimCamera.build(FACE_PHOTO)
    ahead = detector.detect(camera.frame(Posture(HeadPose(), (10, 10), 0)))[0]
    turned = detector.detect(camera.frame(Posture(HeadPose(yaw=15), (10, 10), 0)))[0]
    assert turned[0] > ahead[0] + 50  # turning left moves the scene right in the picture


def test_pixel_offsets_become_head_turns_toward_them() -> None:
    yaw, pitch = pixel_to_angles(600, 100, 640, 480, fx=457)
    assert yaw < 0 and pitch < 0  # right of centre: turn right; above centre: look up
    assert pixel_to_angles(320, 240, 640, 480, fx=457) == (0.0, 0.0)


def test_the_sim_camera_draws_its_scene_at_the_first_frame_and_refuses_an_unreadable_picture_at_once(
    tmp_path: Path,
) -> None:
    camera = SimCamera.build(None)
    assert camera._scene is None  # 8 MiB the device host does not hold until someone looks
    assert camera.frame(Posture(HeadPose(), (10, 10), 0)).shape == (480, 640, 3)
    assert camera._scene is not None
    (tmp_path / "notes.png").write_text("not a picture", encoding="utf-8")
    for unreadable in (tmp_path / "notes.png", tmp_path / "missing.png"):
        with pytest.raises(DeviceError, match="not an image OpenCV can read"):
            SimCamera.build(unreadable)
