"""Camera frames behind the login: the newest of a device, its outlines, and no way out of the folder."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import httpx
import pytest

from rosaos.receipts import Receipt

from .kernel_support import AUTH, TestRuntime

JPEG = b"\xff\xd8\xff\xe0fake-jpeg\xff\xd9"


def write_frame(images: Path, name: str, age: float = 0.0, data: bytes = JPEG) -> Path:
    images.mkdir(parents=True, exist_ok=True)
    path = images / name
    path.write_bytes(data)
    stamp = time.time() - age
    os.utime(path, (stamp, stamp))
    return path


def link_outside(link: Path, target: Path) -> None:
    target.write_bytes(b"outside the images folder")
    link.parent.mkdir(parents=True, exist_ok=True)
    link.symlink_to(target)


async def test_frames_need_the_token(client: httpx.AsyncClient, images_dir: Path) -> None:
    write_frame(images_dir, "kitchen_light-20260101-1.jpg")
    for path in [
        "/devices/kitchen_light/frame",
        "/devices/kitchen_light/frames/kitchen_light-20260101-1.jpg",
    ]:
        response = await client.get(path)
        assert response.status_code == 401, path
        assert JPEG not in response.content


async def test_a_device_without_a_frame_says_so_and_an_unknown_device_is_404(
    client: httpx.AsyncClient,
) -> None:
    nothing = await client.get("/devices/kitchen_light/frame", headers=AUTH)
    assert nothing.status_code == 200
    assert nothing.json()["file"] is None
    unknown = await client.get("/devices/garage_door/frame", headers=AUTH)
    assert unknown.status_code == 404
    assert "kitchen_light" in unknown.json()["detail"]


async def test_the_newest_frame_is_served_with_the_faces_found_in_it(
    client: httpx.AsyncClient, images_dir: Path, runtime: TestRuntime
) -> None:
    write_frame(images_dir, "kitchen_light-20260101-old.jpg", age=60)
    write_frame(images_dir, "kitchen_light-20260101-new.jpg", age=1, data=JPEG + b"new")
    write_frame(images_dir, "kitchen_light_2-20260101-newer.jpg")  # another device's, though a prefix
    faces = {"path": "kitchen_light-20260101-new.jpg", "width": 640, "height": 480, "count": 1}
    faces["faces"] = [{"x": 10, "y": 20, "width": 30, "height": 40, "looks_like": "Ada"}]
    picture = Receipt(
        device="kitchen_light",
        tool="take_picture",
        ok=True,
        started=1.0,
        duration=0.1,
        result=json.dumps({"path": "kitchen_light-20260101-new.jpg", "width": 640, "height": 480}),
    )
    found = Receipt(
        device="kitchen_light",
        tool="detect_faces",
        ok=True,
        started=2.0,
        duration=0.1,
        result=json.dumps(faces),
    )
    assert runtime.activity is not None
    await runtime.activity.record(1, 7, [picture, found])

    info = (await client.get("/devices/kitchen_light/frame", headers=AUTH)).json()
    assert info["file"] == "kitchen_light-20260101-new.jpg"
    assert (info["width"], info["height"]) == (640, 480)
    assert info["boxes"] == [{"x": 10, "y": 20, "width": 30, "height": 40, "label": "Ada"}]
    assert info["boxes_from"] == "detect_faces"
    image = await client.get(f"/devices/kitchen_light/frames/{info['file']}", headers=AUTH)
    assert image.status_code == 200
    assert image.content == JPEG + b"new"
    assert image.headers["content-type"] == "image/jpeg"


@pytest.mark.parametrize(
    "file",
    [
        "..%2Ftoken",
        "..%2F..%2Fetc%2Fpasswd",
        "%2Fetc%2Fpasswd",
        "kitchen_light-1.jpg%2F..%2F..%2Ftoken",
        "kitchen_light_2-20260101-1.jpg",  # another device's frame through this device's route
        "secret.jpg",
        "..",
    ],
)
async def test_no_path_leaves_the_device_s_own_frames(
    client: httpx.AsyncClient, images_dir: Path, tmp_path: Path, file: str
) -> None:
    (tmp_path / "token").write_text("do-not-serve")
    write_frame(images_dir, "kitchen_light-1.jpg")
    write_frame(images_dir, "kitchen_light_2-20260101-1.jpg")
    write_frame(images_dir, "secret.jpg")
    response = await client.get(f"/devices/kitchen_light/frames/{file}", headers=AUTH)
    assert response.status_code in (404, 422), response.text
    assert b"do-not-serve" not in response.content
    assert JPEG not in response.content


async def test_a_symlink_in_the_images_folder_is_not_followed(
    client: httpx.AsyncClient, images_dir: Path, tmp_path: Path
) -> None:
    link_outside(images_dir / "kitchen_light-20260101-1.jpg", tmp_path / "outside.jpg")
    assert (await client.get("/devices/kitchen_light/frame", headers=AUTH)).json()["file"] is None
    response = await client.get("/devices/kitchen_light/frames/kitchen_light-20260101-1.jpg", headers=AUTH)
    assert response.status_code == 404
