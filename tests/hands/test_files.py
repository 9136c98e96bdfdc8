"""Hands as documents: dict, JSON and TOML round trips, and bad files refused (hands/files.py)."""

import dataclasses

import numpy as np
import pytest

from affordgrasp.errors import HandError
from affordgrasp.hands import get_hand, hand_from_dict, hand_to_dict, load_hand, save_hand


@pytest.mark.parametrize("name", ["barrett", "parallel_jaw"])
@pytest.mark.parametrize("suffix", [".json", ".toml"])
def test_round_trip_is_exact(tmp_path, name, suffix):
    hand = get_hand(name)
    path = save_hand(hand, tmp_path / f"{name}{suffix}")
    again = load_hand(path)
    assert hand_to_dict(again) == hand_to_dict(hand)
    q = hand.open_dofs(0.4) + 0.1
    np.testing.assert_array_equal(again.forward_kinematics(q), hand.forward_kinematics(q))
    assert get_hand(str(path)).name == name  # a hand file works wherever a hand name does


def test_bad_documents_name_the_problem(tmp_path):
    doc = hand_to_dict(get_hand("parallel_jaw"))
    del doc["links"][1]["joint"]
    with pytest.raises(HandError, match="needs a joint"):
        hand_from_dict(doc)
    doc = hand_to_dict(get_hand("parallel_jaw"))
    doc["links"][0]["shapes"][0]["pose"] = [[1, 0], [0, 1]]
    with pytest.raises(HandError, match=r"shape pose must be numbers of shape \(4, 4\)"):
        hand_from_dict(doc)
    with pytest.raises(HandError, match="does not exist"):
        load_hand(tmp_path / "nowhere.toml")
    (tmp_path / "bad.toml").write_text("name = [")
    with pytest.raises(HandError, match="not valid toml"):
        load_hand(tmp_path / "bad.toml")
    with pytest.raises(HandError, match=r"\.json or \.toml"):
        save_hand(get_hand("barrett"), tmp_path / "hand.yaml")


def test_registry_lookup_and_replacement():
    from affordgrasp.hands import HANDS, list_hands, register_hand

    custom = dataclasses.replace(get_hand("parallel_jaw"), name="wide_jaw")
    assert register_hand(custom) is custom
    try:
        assert get_hand("wide_jaw") is custom and "wide_jaw" in list_hands()
        with pytest.raises(HandError, match="already registered"):
            register_hand(custom)
    finally:
        HANDS.unregister("wide_jaw")
    with pytest.raises(HandError, match="unknown hand 'wide_jaw'"):
        get_hand("wide_jaw")


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda d: d["dofs"][1].update(upper=np.inf), r"joint's travel .* got inf"),
        (lambda d: d["dofs"][1].update(upper=100.0), r"in \[-6\.28319, 6\.28319\] rad, got 100"),
        (lambda d: d["links"][0]["shapes"][0].update(radius=np.nan), "rounding radius .* nan"),
        (lambda d: d["links"][0]["shapes"][0].update(half_extents=[1e6, 1, 1]), "got 1e\\+06"),
        (lambda d: d["links"][1]["joint"].update(ratio=np.nan), "ratio nan"),
        (lambda d: d["links"][1]["joint"].update(axis=[np.nan, 0, 0]), "must be a unit vector"),
        (lambda d: d["links"][1]["joint"]["origin"][0].__setitem__(3, 5.0), "translation .* 5"),
        (lambda d: d["fingers"][0].update(speeds=[1.0, 0.0]), r"speed .* \[0\.001, 1000\]"),
        (lambda d: d["fingers"][0].update(speeds=[1.0, "fast"]), "malformed hand document"),
    ],
)
def test_every_number_of_a_hand_is_checked(edit, message):
    doc = hand_to_dict(get_hand("barrett"))
    edit(doc)
    with pytest.raises(HandError, match=message):
        hand_from_dict(doc)
