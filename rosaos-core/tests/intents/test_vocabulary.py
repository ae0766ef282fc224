"""What the engine knows of a device: the names people use, its areas, its intents per language."""

from __future__ import annotations

from rosaos.config import DeviceConfig
from rosaos.intents.grammar.vocabulary import DeviceVocabulary, sources_from_config, strip_article
from rosaos.plugins import DriverRegistry

from .intents_support import BULB


def test_the_instance_name_is_spoken_with_spaces_and_by_its_kind() -> None:
    assert DeviceVocabulary(name="kitchen_light", driver="x").spoken_names("en") == [
        "kitchen light",
        "light",
    ]


def test_aliases_lose_their_article() -> None:
    source = DeviceVocabulary(name="lamp_1", driver="x", aliases=("The Lamp", "la lampe"))
    assert source.spoken_names("fr") == ["lamp 1", "lamp", "lampe"]


def test_a_placed_description_gives_two_names_and_an_area() -> None:
    source = DeviceVocabulary(name="l1", driver="x", description="Floor lamp in the living room, by the sofa")
    assert source.spoken_names("en") == ["l1", "floor lamp", "living room lamp", "lamp", "light"]
    assert source.areas("en") == ["living room"]


def test_the_configured_area_comes_first_and_on_the_desk_is_not_an_area() -> None:
    source = DeviceVocabulary(name="lamp", driver="x", description="Smart lamp on the desk", area="bureau")
    assert source.spoken_names("en") == ["lamp", "smart lamp", "desk lamp", "light"]
    assert source.areas("fr") == ["bureau"]


def test_an_unplaced_description_adds_its_kind_and_the_kind_s_synonyms_but_no_area() -> None:
    source = DeviceVocabulary(name="dog", driver="ros", description="Hiwonder PuppyPi quadruped robot dog")
    names = source.spoken_names("en")
    assert names[:2] == ["dog", "robot dog"]
    assert {"pup", "puppy", "robot"} <= set(names)
    assert source.areas("en") == []


def test_a_description_by_a_place_names_the_device_by_its_head() -> None:
    source = DeviceVocabulary(name="l2", driver="x", description="Reading light by the sofa")
    assert {"reading light", "light"} <= set(source.spoken_names("en"))


def test_kind_synonyms_are_per_language() -> None:
    source = DeviceVocabulary(name="chien", driver="x", description="robot dog")
    assert "pup" not in source.spoken_names("fr")


def test_the_intents_file_is_the_one_in_the_engine_language() -> None:
    source = DeviceVocabulary(name="lamp", driver="bulb", intents=BULB)
    english, french = source.intents_file("en"), source.intents_file("fr")
    assert english is not None
    assert english.path == BULB
    assert french is not None
    assert french.path.name == "bulb.fr.yaml"
    assert source.intents_file("de") is None  # no German templates: HA's cover German
    mapping = source.mapping_file()
    assert mapping is not None
    assert mapping.homeassistant is not None


def test_sources_from_config_keep_unknown_drivers_without_intents() -> None:
    [source] = sources_from_config(
        {"drone": DeviceConfig(driver="drone", aliases=["the bird"])}, DriverRegistry()
    )
    assert (source.name, source.intents, source.spoken_names("en")) == ("drone", None, ["drone", "bird"])


def test_strip_article_is_per_language() -> None:
    assert strip_article("  L'Ampoule ", "fr") == "ampoule"
    assert strip_article("the", "en") == "the"


def test_what_a_device_is_on_names_it_when_it_is_a_thing_not_a_room() -> None:
    source = DeviceVocabulary(name="spotify", driver="x", description="Music on the living room speaker")
    assert {"music", "living room speaker", "speaker"} <= set(source.spoken_names("en"))
    assert source.areas("en") == []
