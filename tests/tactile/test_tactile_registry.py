import re

import pytest
import yaml

from tactile.errors import TactileSpecError
from tactile.registry import parse_tactile_block, tactile_sites

BLOCK = """
tactile:
  grouping: side_specific
  normal_convention: inward
  resolution: 24
  sites:
    - name: rh_thumb
      finger: thumb
      group: RTH
      attach_body: rh_thdistal
      pad: {center: [0, 0.009, 0.015], normal: [0, 1, 0], axis: [0, 0, 1], length: 0.025, width: 0.02, curvature_radius: 0.01}
    - name: rh_index
      finger: index
      group: R4F
      attach_body: rh_ffdistal
      pad: {center: [0, 0.008, 0.02], normal: [0, 1, 0], axis: [0, 0, 1], length: 0.03, width: 0.018, curvature_radius: 0.009}
    - {name: rh_middle, finger: middle, group: R4F, attach_body: rh_mfdistal}
"""


def block():
    return yaml.safe_load(BLOCK)["tactile"]


def test_block_parses_and_groups_share_one_surface():
    layout = parse_tactile_block(block(), "shadow.yaml")
    assert layout.groups == ["RTH", "R4F"] and len(layout.sites) == 3
    sites = tactile_sites(layout)
    assert [s.name for s in sites] == ["rh_thumb", "rh_index", "rh_middle"]
    assert sites[1].surface is sites[2].surface and sites[1].attach_body == "rh_ffdistal"
    assert sites[0].surface.shape == (24, 24)


@pytest.mark.parametrize(
    "edit, field",
    [
        (lambda b: b.update(grouping="shared"), "tactile.grouping"),
        (lambda b: b.update(normal_convention="up"), "tactile.normal_convention"),
        (lambda b: b.update(resolution=0), "tactile.resolution"),
        (lambda b: b["sites"][1].pop("attach_body"), "tactile.sites[1].attach_body"),
        (lambda b: b["sites"][2].update(name="rh_index"), "tactile.sites[2].name"),
        (lambda b: b["sites"][1]["pad"].pop("normal"), "tactile.sites[1].pad.normal"),
        (lambda b: b["sites"][2].update(pad=dict(b["sites"][1]["pad"], width=0.017)), "tactile.sites[2].pad"),
        (lambda b: b["sites"][1].pop("pad"), "tactile.sites[1].pad"),
    ],
)
def test_block_errors_name_the_field(edit, field):
    raw = block()
    edit(raw)
    with pytest.raises(TactileSpecError, match=rf"shadow\.yaml: field '{re.escape(field)}'"):
        parse_tactile_block(raw, "shadow.yaml")
