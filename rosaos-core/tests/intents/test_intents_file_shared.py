"""A hundred lamps of one driver share its ``intents.yaml``: it is parsed once, not per device.

Parsing it per device was most of the kernel's start-up CPU with a hundred lamps. A file that
changes on disk is read again.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import rosaos_tapo
from rosaos.intents.grammar.vocabulary import DeviceVocabulary

TAPO_INTENTS = Path(rosaos_tapo.__file__).parent / "intents.yaml"


def test_devices_of_one_driver_share_one_parsed_intents_file(tmp_path: Path) -> None:
    intents = tmp_path / "intents.yaml"
    shutil.copy(TAPO_INTENTS, intents)
    lamps = [DeviceVocabulary(name=f"lamp_{k}", driver="tapo", intents=intents) for k in range(3)]
    files = [lamp.mapping_file() for lamp in lamps]
    assert files[0] is not None
    assert files[0] is files[1] is files[2]
    assert lamps[0].intents_file("en") is lamps[1].intents_file("en")


def test_a_changed_intents_file_is_read_again(tmp_path: Path) -> None:
    intents = tmp_path / "intents.yaml"
    shutil.copy(TAPO_INTENTS, intents)
    before = DeviceVocabulary(name="lamp", driver="tapo", intents=intents).mapping_file()
    intents.write_text(intents.read_text(encoding="utf-8") + "\n# edited\n", encoding="utf-8")
    after = DeviceVocabulary(name="lamp", driver="tapo", intents=intents).mapping_file()
    assert before is not None and after is not None
    assert after is not before
    assert after.actions == before.actions
