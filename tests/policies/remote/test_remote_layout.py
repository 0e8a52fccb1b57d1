"""Fixed-width (32-slot) action and state layouts: arm joints kept, hand joints reduced to a synergy basis from
the demonstrations, its reconstruction error reported, the same file applied on both sides of the wire."""

import json
import threading

import numpy as np
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from episodes.reader import EpisodeReader
from policies.learned import LearnedPolicy
from policies.remote import RemotePolicy, make_server, server_url
from policies.remote.layout import compute_layout, embodiment_layout, load_layout, save_layout
from policies.rollouts import run_rollouts
from sim.errors import SpecError, UnknownNameError

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


def _demo_arrays(paths):
    with EpisodeReader(paths[0]) as r:
        return r.read("action/action").astype(float), r.read("robot/qpos").astype(float)


def test_the_32_slot_layout_keeps_the_arms_and_reduces_the_hands(policy_episodes, tmp_path):
    layout = compute_layout(policy_episodes)
    # ur5_rh5dg2: 24 actuators fit (padded), 36 joints do not: 12 arm joints + 10 synergies per hand
    assert layout.dim == 32 and layout.action.used == 24 and layout.report["action"]["rms_rad"] == 0.0
    assert layout.state.used == 32 and [h["synergies"] for h in layout.report["state"]["hands"]] == [10, 10]
    actions, qpos = _demo_arrays(policy_episodes)
    z = layout.state.encode(qpos)
    assert z.shape == (len(qpos), 32)
    arm = [layout.state.names.index(n) for n in layout.state.kept]
    assert np.array_equal(z[:, :12], qpos[:, arm])                        # arm joints pass through untouched
    back = layout.state.decode(z)
    assert np.abs(back - qpos).max() <= layout.report["state"]["max_abs_rad"] + 1e-12
    assert np.array_equal(layout.action.decode(layout.action.encode(actions)), actions)
    # the file repeats byte for byte and reads back to the same mapping
    save_layout(layout, tmp_path / "a.yaml")
    save_layout(compute_layout(policy_episodes), tmp_path / "b.yaml")
    assert (tmp_path / "a.yaml").read_bytes() == (tmp_path / "b.yaml").read_bytes()
    again = load_layout(tmp_path / "a.yaml")
    assert np.array_equal(again.state.encode(qpos), z) and again.content_hash == layout.content_hash


def test_a_narrower_head_reduces_the_actions_and_reports_the_error(policy_episodes):
    layout = compute_layout(policy_episodes, dim=20)             # 12 arm actuators + 4 synergies per 6-actuator hand
    actions, _ = _demo_arrays(policy_episodes)
    report = layout.report["action"]
    assert report["reduced"] and [h["synergies"] for h in report["hands"]] == [4, 4]
    assert all(0.0 < h["variance_retained"] <= 1.0 for h in report["hands"])
    err = layout.action.decode(layout.action.encode(actions)) - actions
    assert report["max_abs_rad"] >= np.abs(err).max() - 1e-12 and report["rms_rad"] > 0
    full = compute_layout(policy_episodes, dim=24)               # every synergy kept: exact up to rounding
    assert full.report["action"]["rms_rad"] < 1e-9


def test_the_declared_layout_fits_its_embodiment_and_bad_files_name_the_field(tmp_path):
    layout = embodiment_layout(EMBODIMENT)
    assert layout.embodiment == EMBODIMENT and layout.report["state"]["rms_rad"] < 1e-3
    with pytest.raises(UnknownNameError, match="valid embodiment layout names: .*ur5_rh5dg2"):
        embodiment_layout("ur5_nohand")
    raw = layout.to_dict()
    raw["state"]["kept"] = raw["state"]["kept"][:-1]
    import yaml
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(raw))
    with pytest.raises(SpecError, match="bad.yaml: field 'state': expected kept and synergy names that together "
                                        "cover every name once"):
        load_layout(tmp_path / "bad.yaml")


@pytest.fixture(scope="module")
def checkpoint(remote_checkpoint):
    return remote_checkpoint


def test_both_sides_apply_the_layout_the_server_declares(policy_episodes, checkpoint):
    layout = compute_layout(policy_episodes, dim=20)             # lossy both ways: state and actions
    served = LearnedPolicy(checkpoint)
    server = make_server(served, "tcp", port=0, layout=layout)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        remote = RemotePolicy(server_url("tcp", server.address))      # the layout comes with the spec
        assert remote.layout.content_hash == layout.content_hash
        spec = served.observation_spec
        _, qpos = _demo_arrays(policy_episodes)
        obs = {"images": {v: np.full((1, spec.height, spec.width, 3), 90, np.uint8) for v in spec.views},
               "state": qpos[5:6], "tick": 0, "instruction": "x"}
        remote.reset(0, "x")
        got = remote.act(obs)
        # what the wire does: state encoded by the client, decoded by the server; actions the other way
        local = LearnedPolicy(checkpoint)
        local.reset(0, "x")
        expect = local.act({**obs, "state": layout.state.decode(layout.state.encode(obs["state"]))})
        assert np.array_equal(got, layout.action.decode(layout.action.encode(expect)))
        assert got.shape == (1, 24) and not np.array_equal(got, expect)          # 20 slots lose a little
        rows = run_rollouts(remote, TASK, EMBODIMENT, "inv_equi", [], 1, max_steps=3)
        assert rows[0]["termination"] == "horizon"
    finally:
        server.close()


def test_b2d_layout_writes_the_file_and_prints_the_error(policy_episodes, tmp_path):
    out = tmp_path / "layout.yaml"
    result = CliRunner().invoke(cli, ["layout", str(policy_episodes[0].parent), "--out", str(out)])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.stdout[result.stdout.index("{"):])
    assert summary["embodiment"] == EMBODIMENT and summary["state"]["slots_used"] == 32
    assert load_layout(out).report["state"] == summary["state"]


def test_every_declared_layout_loads_and_names_its_embodiments_actuators():
    from policies.remote.layout import LAYOUTS, _groups

    declared = sorted(LAYOUTS.glob("*.yaml"))
    assert declared, "no declared layouts"
    for path in declared:
        layout = load_layout(path)
        assert layout.embodiment == path.stem and layout.dim == 32
        assert layout.to_dict()["action"]["names"] == _groups(path.stem, "action")[0], path.name
