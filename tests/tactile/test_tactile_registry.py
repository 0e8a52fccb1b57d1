import copy
import re

import numpy as np
import pytest
import yaml

from sim.embodiment import DescriptionError, hand_names, load_hand
from sim.embodiment.description import parse_tactile_block, read_hand_file
from sim.embodiment.mirror import M
from tactile.registry import surface_assets

BLOCK = """
tactile:
  grouping: side_specific
  normal_convention: inward
  resolution: 24
  pad_friction: [1.3, 0.02, 0.002]
  groups:
    TH:
      assets: {right: RTH, left: LTH}
      pad: &TH {center: [0, 0.009, 0.015], normal: [0, 1, 0], axis: [0, 0, 1], length: 0.025, width: 0.02, curvature_radius: 0.01}
    4F:
      assets: {right: R4F, left: L4F}
      pad: &4F {center: [0, 0.008, 0.02], normal: [0, 1, 0], axis: [0, 0, 1], length: 0.03, width: 0.018, curvature_radius: 0.009}
  sites:
    - {name: thumb_tip, finger: thumb, group: TH, attach_body: rh_thdistal, pad: *TH}
    - {name: index_tip, finger: index, group: 4F, attach_body: rh_ffdistal, pad: *4F}
    - {name: middle_tip, finger: middle, group: 4F, attach_body: rh_mfdistal, pad: *4F}
"""

# The paper's Table "Tactile surface-map grouping policy for the twelve Bench2Dex hands".
PAPER_POLICY = {
    "sharpa": "side_shared",
    "rh5dg2": "side_specific", "shadow": "side_specific", "schunk_svh": "side_specific", "wuji": "side_specific",
    "allegro": "side_specific", "orca": "side_specific", "leap": "side_specific", "dexhand021": "side_specific",
    "rh56dfx": "per_finger", "ability": "per_finger", "revo2": "per_finger",
}


LINKS = {"rh_thdistal", "rh_ffdistal", "rh_mfdistal", "rh_rfdistal"}
FINGERS = ["thumb", "index", "middle"]


def block():
    return copy.deepcopy(yaml.safe_load(BLOCK)["tactile"])


def parse(raw, source="shadow.yaml", fingers=FINGERS):
    return parse_tactile_block(raw, source, LINKS, fingers)


def test_block_parses_into_groups_assets_and_a_site_map():
    layout = parse(block())
    assert layout.grouping == "side_specific" and list(layout.groups) == ["TH", "4F"]
    assert layout.groups["4F"].sites == ("index_tip", "middle_tip")
    assert layout.site_assets() == {
        "right_thumb_tip": "RTH", "right_index_tip": "R4F", "right_middle_tip": "R4F",
        "left_thumb_tip": "LTH", "left_index_tip": "L4F", "left_middle_tip": "L4F",
    }
    with pytest.raises(KeyError, match="no tactile site 'ring_tip'"):
        layout.asset_of("left", "ring_tip")
    assets = surface_assets(layout)
    assert sorted(assets) == ["L4F", "LTH", "R4F", "RTH"] and assets["R4F"].shape == (24, 24)
    assert assets["L4F"].group == "L4F"
    # a left asset is the right one reflected by the embodiment's mirror, on the same grid
    right, left = assets["R4F"], assets["L4F"]
    assert np.array_equal(left.point_mm, (right.point_mm @ M.T.astype(np.float32)) + 0)
    assert np.array_equal(left.normal, (right.normal @ M.T.astype(np.float32)) + 0)
    assert not np.array_equal(left.point_mm, right.point_mm)


def test_side_shared_serves_both_hands_with_one_asset():
    raw = block()
    raw["grouping"] = "side_shared"
    raw["groups"]["TH"]["assets"] = {"right": "TH", "left": "TH"}
    raw["groups"]["4F"]["assets"] = {"right": "4F", "left": "4F"}
    layout = parse(raw, "sharpa.yaml")
    assert set(layout.site_assets().values()) == {"TH", "4F"}
    assert sorted(surface_assets(layout)) == ["4F", "TH"]


def _set_policy(b, grouping, **assets):
    b["grouping"] = grouping
    for group, (right, left) in assets.items():
        b["groups"][group]["assets"] = {"right": right, "left": left}


def _per_finger_with_shared_group(b):
    b["grouping"] = "per_finger"


def _thumb_in_4f(b):
    b["sites"][0].update(group="4F", pad=b["groups"]["4F"]["pad"])


def _asymmetric_shared_pad(b):
    _set_policy(b, "side_shared", TH=("TH", "TH"), **{"4F": ("4F", "4F")})
    pad = dict(b["groups"]["TH"]["pad"], center=[0.002, 0.009, 0.015])
    b["groups"]["TH"]["pad"] = pad
    b["sites"][0]["pad"] = pad


@pytest.mark.parametrize(
    "edit, field, words",
    [
        (lambda b: b.update(grouping="shared"), "tactile.grouping", "one of 'side_shared', 'side_specific' or 'per_finger'"),
        (lambda b: b.update(normal_convention="up"), "tactile.normal_convention", "one of 'inward' or 'outward'"),
        (lambda b: b.update(resolution=0), "tactile.resolution", "an integer > 0"),
        (lambda b: b.update(layout="x"), "tactile.layout", "a tactile key from ['grouping'"),
        (lambda b: b.pop("groups"), "tactile.groups", "a value (field is missing)"),
        (lambda b: b.update(groups={}), "tactile.groups", "at least 1 item"),
        (lambda b: b["groups"]["TH"]["assets"].pop("left"), "tactile.groups.TH.assets.left", "a value (field is missing)"),
        (lambda b: b["groups"]["4F"]["pad"].pop("normal"), "tactile.groups.4F.pad.normal", "a value"),
        (lambda b: b["sites"][1].pop("attach_body"), "tactile.sites[1].attach_body", "a value (field is missing)"),
        (lambda b: b["sites"][1].update(attach_body="rh_ffmiddle"), "tactile.sites[1].attach_body",
         "a link of this hand"),
        (lambda b: b["sites"][1].update(finger="pinky"), "tactile.sites[1].finger",
         "one of the fingers thumb, index, middle"),
        (lambda b: b["sites"].pop(2), "tactile.sites", "one site per finger"),
        (lambda b: b.update(pad_condim=2), "tactile.pad_condim", "one of 1, 3, 4 or 6"),
        (lambda b: b.update(pad_friction=[1.0, 0.1]), "tactile.pad_friction", "a list of 3 items"),
        (lambda b: b["sites"][2].update(name="index_tip"), "tactile.sites[2].name", "unique"),
        (lambda b: b["sites"][2].update(group="MID"), "tactile.sites[2].group", "one of the groups TH, 4F"),
        # a group whose pads differ
        (lambda b: b["sites"][2].update(pad=dict(b["sites"][1]["pad"], width=0.017)), "tactile.sites[2].pad",
         "the pad of group '4F'"),
        (lambda b: b["sites"][1].pop("pad"), "tactile.sites[1].pad", "the pad of group '4F'"),
        # the policy's shape
        (_per_finger_with_shared_group, "tactile.groups.4F", "one site per group under grouping per_finger"),
        (_thumb_in_4f, "tactile.groups.TH", "at least one site"),
        (lambda b: _set_policy(b, "side_shared"), "tactile.groups.TH.assets", "one asset for both sides"),
        (lambda b: _set_policy(b, "side_specific", TH=("TH", "TH")), "tactile.groups.TH.assets",
         "different right and left assets"),
        (_asymmetric_shared_pad, "tactile.groups.TH.pad", "symmetric under the left/right mirror"),
        (lambda b: _set_policy(b, "side_specific", **{"4F": ("RTH", "L4F")}), "tactile.groups.4F.assets.right",
         "an asset name not used by group 'TH'"),
    ],
)
def test_block_errors_name_the_field(edit, field, words):
    raw = block()
    edit(raw)
    with pytest.raises(DescriptionError, match=rf"shadow\.yaml: field '{re.escape(field)}': expected .*{re.escape(words)}"):
        parse(raw)


def test_thumb_and_fingers_mixed_in_one_group_is_refused():
    raw = block()
    raw["sites"].append({"name": "ring_tip", "finger": "ring", "group": "TH", "attach_body": "rh_rfdistal",
                         "pad": raw["groups"]["TH"]["pad"]})
    with pytest.raises(DescriptionError, match=r"field 'tactile.groups.TH': expected either the thumb sites"):
        parse(raw, fingers=[*FINGERS, "ring"])


def _hand_file_with(tmp_path, edit):
    """A copy of the Sharpa hand file whose tactile block went through ``edit`` (the other blocks intact)."""
    data = yaml.safe_load(load_hand("sharpa").path.read_text())
    edit(data["tactile"])
    path = tmp_path / "sharpa_edited.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_loading_a_hand_file_with_a_bad_policy_or_differing_pads_names_file_and_field(tmp_path):
    assert read_hand_file(_hand_file_with(tmp_path, lambda t: None)).tactile.grouping == "side_shared"
    path = _hand_file_with(tmp_path, lambda t: t.update(grouping="side-shared"))
    with pytest.raises(DescriptionError, match=rf"{re.escape(str(path))}: field 'tactile.grouping'"):
        read_hand_file(path)

    def longer_middle_pad(t):
        t["sites"][2]["pad"] = dict(t["sites"][2]["pad"], length=0.018)

    path = _hand_file_with(tmp_path, longer_middle_pad)
    with pytest.raises(DescriptionError, match=rf"{re.escape(str(path))}: field 'tactile.sites\[2\].pad': "
                                               r"expected the pad of group '4F'"):
        read_hand_file(path)


@pytest.mark.parametrize("hand", hand_names())
def test_catalog_hand_follows_the_papers_grouping_policy(hand):
    assert load_hand(hand).tactile.grouping == PAPER_POLICY[hand]


@pytest.mark.parametrize("hand", hand_names())
def test_catalog_hand_groups_follow_their_policy(hand):
    description = load_hand(hand)
    layout = description.tactile
    assert layout.resolution == 240 and layout.normal_convention == "inward"
    for site in layout.sites:   # the physics pads are the group pads
        assert site.pad.same_as(layout.groups[site.group].pad)
    sizes = sorted(len(g.sites) for g in layout.groups.values())
    fingers = len(description.fingers)
    assert sizes == ([1] * fingers if layout.grouping == "per_finger" else [1, fingers - 1])
    assert len(set(layout.site_assets().values())) == len(layout.groups) * (1 if layout.grouping == "side_shared" else 2)
