"""A remote policy server that is down, slow past the timeout, sends a malformed frame, an oversized length
prefix or an action of the wrong shape ends that episode as an error naming the server and the fault; the
evaluation goes on with the next episode. b2d's own server binds 127.0.0.1 and refuses oversized messages."""

import threading

import numpy as np
import pytest
from remote_fakes import FAULTS, FaultyServer, HoldStill, glance_spec, closed_port

from policies.closed_loop import run_episode
from policies.interface import PolicyError
from policies.remote import RemotePolicy, make_server, server_url
from policies.rollouts import run_rollouts
from sim.scene.builder import demonstration_scene

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
TIMEOUT = 0.5

EXPECTED = {"down": "cannot connect", "slow": f"no reply .* within {TIMEOUT:g} s",
            "malformed": "malformed frame", "oversized": "over the limit of",
            "wrong_shape": r"action chunk of shape \(1, 3\); expected \(rows >= 1, ",
            "error": "model exploded"}


@pytest.fixture(scope="module")
def scene():
    return demonstration_scene(TASK, EMBODIMENT)


@pytest.fixture(scope="module")
def spec(scene):
    return glance_spec(scene)


def _remote(url, spec):
    return RemotePolicy(url, spec=spec, timeout=TIMEOUT, max_bytes=16 * 1024)


@pytest.mark.parametrize("protocol", ["tcp", "ws"])
@pytest.mark.parametrize("fault", ("down",) + FAULTS)
def test_each_fault_ends_the_episode_as_an_error_naming_the_server_and_the_fault(protocol, fault, scene, spec):
    server = FaultyServer(protocol, fault, spec.action_spec.dim) if fault != "down" else None
    url = server.url if server else f"{protocol}://127.0.0.1:{closed_port()}"
    try:
        outcome = run_episode(_remote(url, spec), scene, seed=0, max_steps=3)
    finally:
        if server:
            server.close()
    record = outcome.record
    assert record["termination"] == "error"
    assert record["error"].startswith(f"policy server {url}: ")
    assert __import__("re").search(EXPECTED[fault], record["error"]), record["error"]


@pytest.mark.parametrize("protocol", ["tcp", "ws"])
def test_the_evaluation_goes_on_with_the_next_episode_after_a_fault(protocol, spec):
    # the first query times out; the client connects again for the next episode, which runs to its horizon
    server = FaultyServer(protocol, "slow", spec.action_spec.dim, faulty=lambda i: i == 0)
    try:
        rows = run_rollouts(_remote(server.url, spec), TASK, EMBODIMENT, "inv_equi", [], 2, max_steps=3)
    finally:
        server.close()
    assert [r["termination"] for r in rows] == ["error", "horizon"]
    assert server.url in rows[0]["error"] and "no reply" in rows[0]["error"]
    assert rows[1]["control_steps"] == 3


def _serve(policy, protocol, **kw):
    server = make_server(policy, protocol, port=0, **kw)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


@pytest.mark.parametrize("protocol", ["tcp", "ws"])
def test_the_server_binds_loopback_and_refuses_oversized_messages(protocol, spec):
    server = _serve(HoldStill(spec), protocol, max_bytes=2048)
    try:
        host, port = server.address
        assert host == "127.0.0.1"
        url = server_url(protocol, (host, port))
        client = RemotePolicy(url, timeout=5)                     # the spec comes from the server
        assert client.name == "glance" and client.action_spec == spec.action_spec
        client.reset(0, "hold still")
        small = {"state": np.zeros((1, len(spec.observation_spec.state_names)))}
        assert client.act(small).shape == (1, spec.action_spec.dim)
        with pytest.raises(PolicyError, match=f"policy server {url}: .*(over the limit of 2048|over its size limit)"):
            client.act({"state": np.zeros((1, 4096))})
        # the server goes on serving: a fresh episode works
        client.reset(1, "hold still")
        assert client.act(small).shape == (1, spec.action_spec.dim)
        client.close()
    finally:
        server.close()


def test_a_bad_url_and_a_server_that_cannot_describe_its_policy_are_clear_errors(spec):
    with pytest.raises(ValueError, match="expected a scheme of tcp://, ws://"):
        RemotePolicy("http://127.0.0.1:80", spec=spec)
    server = FaultyServer("ws", "error", spec.action_spec.dim)
    try:
        with pytest.raises(PolicyError, match="does not describe its policy: declare its spec"):
            RemotePolicy(server.url, timeout=TIMEOUT)
    finally:
        server.close()
