"""The checking rules of ``../shared/bench/README.md``, one behaviour per test."""

from __future__ import annotations

from rosaos.bench.expect import device_differences, meets, reply_matches, values_equal, world_differences

# --- plain values and tolerance ---------------------------------------------------------------


def test_equal_values_match() -> None:
    assert values_equal("So What", "So What")


def test_numbers_match_within_two_percent() -> None:
    assert values_equal(200, 203.9)
    assert not values_equal(200, 204.1)


def test_numbers_match_within_five_hundredths_when_that_is_larger() -> None:
    assert values_equal(0, 0.05)
    assert values_equal(1.0, 1.049)
    assert not values_equal(0, 0.051)


def test_booleans_are_not_numbers() -> None:
    assert not values_equal(True, 1)
    assert not values_equal(0, False)


def test_strings_compare_exactly() -> None:
    assert not values_equal("so what", "So What")


def test_nested_dicts_compare_the_expected_keys_only() -> None:
    assert values_equal({"yaw": 10}, {"yaw": 10.1, "pitch": 3})
    assert not values_equal({"yaw": 10}, {"pitch": 3})


def test_lists_compare_item_by_item_with_tolerance() -> None:
    assert values_equal([0, 10], [0.01, 10.1])
    assert not values_equal([0, 10], [0, 10, 0])


# --- operators ----------------------------------------------------------------------------------


def test_gt_is_strict() -> None:
    assert meets({"gt": 40}, 40, 41)
    assert not meets({"gt": 40}, 40, 40)


def test_lt_is_strict() -> None:
    assert meets({"lt": 3300}, 4000, 2700)
    assert not meets({"lt": 3300}, 4000, 3300)


def test_between_includes_its_ends() -> None:
    assert meets({"between": [100, 140]}, 0, 100)
    assert meets({"between": [100, 140]}, 0, 140)
    assert not meets({"between": [100, 140]}, 0, 140.5)


def test_numeric_operators_fail_on_a_missing_or_non_numeric_value() -> None:
    assert not meets({"gt": 0.1}, 0, None)
    assert not meets({"between": [0, 1]}, 0, True)


def test_contains_ignores_case() -> None:
    assert meets({"contains": "clair de lune"}, None, "Clair de Lune")
    assert not meets({"contains": "jazz"}, None, "Clair de Lune")


def test_contains_fails_on_null() -> None:
    assert not meets({"contains": "good morning"}, "", None)


def test_changed_compares_with_the_initial_value() -> None:
    assert meets({"changed": True}, "So What", "Take Five")
    assert not meets({"changed": True}, "So What", "So What")


def test_changed_ignores_movement_within_tolerance() -> None:
    assert not meets({"changed": True}, 0.5, 0.51)


def test_changed_false_means_kept() -> None:
    assert meets({"changed": False}, 40, 40)


# --- nothing else moves ---------------------------------------------------------------------------


def test_keys_not_named_in_expect_must_keep_their_value() -> None:
    [moved] = device_differences(
        {"on": True}, {"on": False, "brightness": 100}, {"on": True, "brightness": 50}
    )
    assert (moved.key, moved.rule, moved.expected, moved.actual) == ("brightness", "unchanged", 100, 50)


def test_unnamed_keys_may_drift_within_tolerance() -> None:
    assert not device_differences({}, {"x": 0.0, "yaw": 1.0}, {"x": 0.03, "yaw": 1.01})


def test_keys_only_get_state_returns_are_not_checked() -> None:
    assert not device_differences({}, {"on": True}, {"on": True, "rssi": -40})


def test_a_key_missing_from_get_state_counts_as_moved() -> None:
    [moved] = device_differences({}, {"track": None}, {})
    assert (moved.key, moved.present) == ("track", False)


def test_empty_expect_means_change_nothing() -> None:
    differences = world_differences({}, {"lamp": {"on": False}}, {"lamp": {"on": True}})
    assert [str(d) for d in differences] == ["lamp.on: expected unchanged (False), got True"]


def test_nested_state_keeps_the_keys_expect_does_not_name() -> None:
    before = {"head": {"roll": 0, "pitch": 0, "yaw": 0}}
    after = {"head": {"roll": 0, "pitch": 12, "yaw": 30}}
    [moved] = device_differences({"head": {"yaw": {"gt": 15}}}, before, after)
    assert (moved.key, moved.rule) == ("head.pitch", "unchanged")


def test_devices_whose_state_was_not_read_are_skipped() -> None:
    assert not world_differences({"reachy": {"awake": True}}, {"reachy": {"awake": False}}, {})


def test_a_broken_expectation_names_device_key_expected_and_actual() -> None:
    [difference] = world_differences(
        {"spotify": {"volume": {"gt": 40}}}, {"spotify": {"volume": 40}}, {"spotify": {"volume": 40}}
    )
    assert str(difference) == "spotify.volume: expected > 40, got 40"


# --- reply ----------------------------------------------------------------------------------------


def test_reply_matches_when_some_reply_matches() -> None:
    assert reply_matches(r"(?i)\b(no|off|not)\b", ["Checking the kitchen light.", "No, it is off."])


def test_reply_is_searched_not_anchored() -> None:
    assert reply_matches("off", ["The kitchen light is off."])


def test_reply_fails_when_no_reply_matches() -> None:
    assert not reply_matches(r"(?i)\bon\b", ["Which one do you mean?"])


def test_reply_fails_without_replies() -> None:
    assert not reply_matches(".*", [])
