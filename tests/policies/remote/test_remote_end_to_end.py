"""A b2d checkpoint served over each protocol gives the same rollout records as the same checkpoint in
process, seed for seed; `b2d serve` and `b2d eval --remote` do the same from the command line."""

import json
import signal
import subprocess
import sys
import threading

import pandas as pd
import pytest
from click.testing import CliRunner

from b2d_cli.main import cli
from policies.closed_loop import run_episode
from policies.config import load_policy_config
from policies.learned import LearnedPolicy
from policies.remote import RemotePolicy, make_server, server_url
from policies.rollouts import run_rollouts
from policies.train import train_policy
from sim.scene.builder import demonstration_scene

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"


@pytest.fixture(scope="module")
def checkpoint(remote_checkpoint):
    return remote_checkpoint


@pytest.fixture(scope="module")
def in_process_rows(checkpoint):
    return run_rollouts(LearnedPolicy(checkpoint), TASK, EMBODIMENT, "inv_equi", [], 1, max_steps=6)


@pytest.mark.parametrize("protocol", ["tcp", "ws"])
def test_a_rollout_through_the_server_gives_the_in_process_records(checkpoint, in_process_rows, protocol):
    server = make_server(LearnedPolicy(checkpoint), protocol, port=0)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        remote = RemotePolicy(server_url(protocol, server.address))     # spec, setting and anchors from the server
        assert remote.observation_spec == LearnedPolicy(checkpoint).observation_spec
        assert remote.spec.setting == {"task": TASK, "embodiment": EMBODIMENT} and remote.spec.anchors
        rows = run_rollouts(remote, TASK, EMBODIMENT, "inv_equi", [], 1, max_steps=6)
        remote.close()
    finally:
        server.close()
    assert [(r["termination"], r["control_steps"]) for r in rows] == [("horizon", 6)]
    assert rows == in_process_rows


@pytest.fixture(scope="module")
def dp_checkpoint(policy_episodes, tmp_path_factory):
    out = tmp_path_factory.mktemp("remote_dp") / "dp"
    train_policy(load_policy_config("dp", "tiny"), policy_episodes, out, steps=1)
    return out


def test_the_episode_seed_reaches_a_sampling_policy_across_the_wire(dp_checkpoint):
    """Diffusion draws its noise from the episode's seed: the served policy executes the in-process
    actions bit for bit at the same seed over either protocol, and other actions at another seed."""
    def actions(policy, seed):
        return run_episode(policy, demonstration_scene(TASK, EMBODIMENT), seed=seed, max_steps=3).recording.action

    local = actions(LearnedPolicy(dp_checkpoint), 7)
    for protocol, seeds in (("tcp", (7,)), ("ws", (7, 8))):
        server = make_server(LearnedPolicy(dp_checkpoint), protocol, port=0)
        threading.Thread(target=server.serve_forever, daemon=True).start()
        try:
            remote = RemotePolicy(server_url(protocol, server.address))
            served = {seed: actions(remote, seed) for seed in seeds}
        finally:
            server.close()
        assert served[7].tobytes() == local.tobytes(), protocol
    assert served[8].tobytes() != local.tobytes()


def _ignore_stop_signals() -> None:
    """As some parents leave a child (an ignored disposition survives exec)."""
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def test_b2d_serve_then_b2d_eval_remote(checkpoint, tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "b2d_cli.main", "serve", "--checkpoint", str(checkpoint),
                             "--protocol", "tcp", "--port", "0"], stderr=subprocess.PIPE, text=True,
                            preexec_fn=_ignore_stop_signals)
    try:
        first = proc.stderr.readline()
        assert "serving act_tiny (citrus_plate_loading on ur5_rh5dg2) at tcp://127.0.0.1:" in first, first
        url = first.split(" at ")[-1].strip()
        records = tmp_path / "records.parquet"
        result = CliRunner().invoke(cli, ["eval", "--remote", url, "--channel", "none", "--episodes", "1",
                                          "--max-steps", "3", "--json", "--out", str(records)])
        assert result.exit_code == 0, result.output
        cells = json.loads(result.stdout[result.stdout.index("["):])
        assert [(c["channel"], c["N"]) for c in cells] == [("none", 1)]
        row = pd.read_parquet(records).iloc[0]
        assert row["policy"] == "act_tiny" and row["termination"] == "horizon" and row["anchor"]
    finally:
        proc.terminate()
        # a SIGTERM stops it cleanly although its parent ignored SIGTERM
        assert proc.wait(timeout=30) == 0


def test_eval_remote_bad_input_is_one_line(tmp_path):
    from remote_fakes import closed_port
    runner = CliRunner()
    down = runner.invoke(cli, ["eval", "--remote", f"tcp://127.0.0.1:{closed_port()}"])
    assert down.exit_code == 2 and "cannot connect" in down.output and "--spec FILE" in down.output
    both = runner.invoke(cli, ["eval"])
    assert both.exit_code == 2 and "pass --checkpoint DIR or --remote URL" in both.output
    bad = tmp_path / "spec.yaml"
    bad.write_text("name: x\nobservation_spec: {views: [front], width: 64, height: 48, rate_hz: 10}\n"
                   "actions_per_query: 1\n")
    declared = runner.invoke(cli, ["eval", "--remote", "tcp://127.0.0.1:1", "--spec", str(bad)])
    assert declared.exit_code == 2 and "spec.yaml: field 'action_names': expected a value" in declared.output
    bad.write_text("name: x\nobservation_spec: {views: [front], width: 64, heigth: 48, rate_hz: 10}\n"
                   "action_names: [a]\nactions_per_query: 0\n")
    declared = runner.invoke(cli, ["eval", "--remote", "tcp://127.0.0.1:1", "--spec", str(bad)])
    assert declared.exit_code == 2 and "spec.yaml: field 'observation_spec.height': expected a value" in declared.output
    assert "field 'observation_spec.heigth': expected an observation_spec key from ['views'" in declared.output
    assert "field 'actions_per_query': expected an integer > 0 (got 0)" in declared.output
