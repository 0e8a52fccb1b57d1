"""The live session in-process: the start / save / discard / home protocol, homing that resets the
filters and wrist anchors, the horizon, and the three control channels (script, TCP port, keys)."""

from __future__ import annotations

import json
import os
import socket
import termios
import threading
import time

import numpy as np
import pytest

from episodes.raw import read_raw
from sim.registry import names
from sim.scene.sample import task_seed
from sim.state_io import get_state
from teleop.recorder import home
from teleop.session import TeleopSession
from teleop.session_control import (ControlPort, ControlScriptError, KeyboardControl, ScriptControl, parse_script,
                                    read_control_file)
from teleop.session_inputs import open_input
from teleop.streams import StepFlag, write_stream
from test_teleop_session_streams import clean_frame

TASK, EMBODIMENT = "citrus_plate_loading", "ur5_rh5dg2"
FRAMES = 240


@pytest.fixture(scope="module")
def stream_path(tmp_path_factory):
    frames = [clean_frame(k, FRAMES) for k in range(FRAMES)]
    return write_stream(tmp_path_factory.mktemp("stream") / "clean.npz", frames)


def session(stream_path, out_dir, **kw) -> TeleopSession:
    return TeleopSession(TASK, EMBODIMENT, open_input([f"recorded:{stream_path}"]), out_dir, say=lambda m: None, **kw)


def arm_ids(s: TeleopSession) -> list[int]:
    lay = s.scene.layout
    return [s.scene.model.actuator(a).id for side in ("left", "right") for a in lay.sides[side].arm_actuators]


def test_start_save_discard_home_protocol(stream_path, tmp_path):
    s = session(stream_path, tmp_path)
    assert s.handle("save")[0] is False and "start one first" in s.handle("save")[1]
    assert s.handle("discard")[0] is False
    assert s.handle("home") == (True, "home")
    for _ in range(5):
        s.step()                                        # idle: not recorded
    ok, msg = s.handle("start")
    assert ok and "recording episode 0000" in msg
    assert np.array_equal(s.episode.initial_state, get_state(s.scene.model, home(s.scene)))   # homed first
    assert s.handle("start")[0] is False and s.handle("home")[0] is False     # one episode at a time
    for _ in range(20):
        s.step()
    ok, msg = s.handle("discard")
    assert ok and "20 steps" in msg and s.episode is None and not list(tmp_path.iterdir())
    assert s.episode_id == "0000"                        # a retry of the same scene sample
    s.handle("start")
    for _ in range(15):
        s.step()
    ok, msg = s.handle("save")
    assert ok and "15 steps" in msg, msg
    rec = read_raw(tmp_path / "episode_0000.raw.h5")
    task_index = names("tasks").index(TASK)
    assert rec.num_steps == 15 and rec.operator == "teleop:recorded" and rec.seed == task_seed(task_index, 0)
    assert rec.extra["episode_record"]["termination"] == "saved" and rec.extra["step_flag_bits"]["UNREACHABLE"] == 16
    assert s.episode_id == "0001" and s.seed == task_seed(task_index, 1)      # the next scene sample
    assert [e.episode_id for e in s.saved] == ["0000"]
    assert session(stream_path, tmp_path).episode_id == "0001"                # existing files are skipped
    assert s.handle("quit")[0] and s.quit_requested


def test_start_homes_and_resets_the_wrist_anchors(stream_path, tmp_path):
    s = session(stream_path, tmp_path)
    ids = arm_ids(s)
    home_arm = s.driver.commander.home_ctrl[ids]
    for _ in range(120):                    # the operator's wrist drifts away from where it started
        s.step()
    assert np.abs(s.data.ctrl[ids] - home_arm).max() > 0.01
    s.handle("start")
    s.step()
    # the first wrist pose after start is the new anchor: the arm is commanded to stay home
    assert np.allclose(s.episode.buf.arrays["action"][0, ids], home_arm, atol=1e-6)


def test_recording_stops_at_the_horizon_and_waits_for_save(stream_path, tmp_path):
    s = session(stream_path, tmp_path, max_steps=12)
    s.handle("start")
    for _ in range(20):
        s.step()
    assert s.episode.steps == 12 and not s.recording and s.ended_by == "horizon"
    assert "stopped (horizon)" in s.handle("status")[1]
    assert s.handle("save")[0]
    rec = read_raw(tmp_path / "episode_0000.raw.h5")
    assert rec.num_steps == 12 and rec.extra["episode_record"]["termination"] == "horizon"


def test_control_port_drives_a_running_session(stream_path, tmp_path):
    s = session(stream_path, tmp_path)
    port = ControlPort("127.0.0.1", 0)
    assert port.address[0] == "127.0.0.1"
    runner = threading.Thread(target=s.run, args=([port],), kwargs={"realtime": False}, daemon=True)
    runner.start()
    try:
        with socket.create_connection(port.address, timeout=60) as conn, conn.makefile("rwb") as io:
            def ask(line: str) -> str:
                io.write(line.encode() + b"\n")
                io.flush()
                return io.readline().decode().strip()

            assert ask("save").startswith("error no episode")
            assert ask("start").startswith("ok home; recording episode 0000")
            assert ask("bogus").startswith("error unknown command 'bogus'")
            assert "episode 0000 recording" in ask("status")
            saved = ask("save")
            assert saved.startswith("ok saved") and "episode_0000.raw.h5" in saved
            assert ask("quit") == "ok bye"
        runner.join(60)
        assert not runner.is_alive()
    finally:
        port.close()
    rec = read_raw(tmp_path / "episode_0000.raw.h5")
    assert rec.num_steps > 0 and rec.operator == "teleop:recorded"


def test_keys_from_a_terminal_become_commands():
    master, slave = os.openpty()
    before = termios.tcgetattr(slave)
    said = []
    keys = KeyboardControl(slave, said.append)
    try:
        assert not termios.tcgetattr(slave)[3] & termios.ICANON       # single keys, no Enter
        os.write(master, b"sx?q")
        requests = keys.poll(0)
        assert [r.command for r in requests] == ["start", "status", "quit"]
        assert any("key 'x' does nothing" in m for m in said)
        requests[0].reply(True, "recording")
        assert said[-1] == "start: recording"
        assert keys.poll(1) == []
    finally:
        keys.close()
        assert termios.tcgetattr(slave) == before                     # the terminal is given back
        os.close(master)
        os.close(slave)


def test_scripts_run_commands_at_their_control_steps(tmp_path):
    items = parse_script("start; wait 0.5 ;save;wait 0.1;quit")
    assert [(i.command, i.wait_steps) for i in items] == [("start", 0), ("wait", 30), ("save", 0), ("wait", 6),
                                                           ("quit", 0)]
    said = []
    script = ScriptControl(items, said.append)
    due = {step: [r.command for r in script.poll(step)] for step in range(40)}
    assert {k: v for k, v in due.items() if v} == {0: ["start"], 30: ["save"], 36: ["quit"]}
    assert script.done(36) and not ScriptControl(items, said.append).done(0)
    refuse = ScriptControl(parse_script("save"), said.append)
    refuse.poll(0)[0].reply(False, "no episode to save")
    assert refuse.refused == ["save at step 0: no episode to save"]
    f = tmp_path / "session.ctl"
    f.write_text("# warm up\nwait 1\nstart\nwait 2   # two seconds\nsave\n")
    assert [(i.command, i.wait_steps) for i in read_control_file(f)] == [("wait", 60), ("start", 0), ("wait", 120),
                                                                          ("save", 0)]


@pytest.mark.parametrize("text, words", [
    ("start;jump", "item 'jump': expected one of start, save"),
    ("wait", "expected 'wait SECONDS'"),
    ("wait -1", "expected 'wait SECONDS'"),
    ("wait soon", "expected 'wait SECONDS'"),
    ("start now", "item 'start now'"),
])
def test_bad_scripts_say_what_was_expected(text, words):
    with pytest.raises(ControlScriptError, match=words):
        parse_script(text)


def test_a_bad_control_file_names_the_file_and_line(tmp_path):
    f = tmp_path / "s.ctl"
    f.write_text("start\nwait 1\nsaev\n")
    with pytest.raises(ControlScriptError, match=r"s\.ctl, line 3: item 'saev'"):
        read_control_file(f)


def test_a_live_device_is_clocked_by_its_arrivals(tmp_path):
    source = open_input(["arkit:0"], stream_hz=60)
    try:
        s = TeleopSession(TASK, EMBODIMENT, source, tmp_path, say=lambda m: None)
        s.handle("start")
        sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        period = 16_666_667

        def send(t_ns: int) -> None:
            f = clean_frame(0, 2)
            packet = {"t_ns": t_ns, **{side: {"pos": f.wrist_pos[i].tolist(), "quat_wxyz": f.wrist_quat[i].tolist()}
                                       for i, side in enumerate(("left", "right"))}}
            sender.sendto(json.dumps(packet).encode(), source.stream.address)
            time.sleep(0.05)                 # loopback delivery

        send(5 * 10**9)                      # the phone's clock, unrelated to the session's
        s.step()
        send(5 * 10**9 + period)
        s.step()
        s.step()                             # nothing arrived: the next frame was due
        send(5 * 10**9 + 3 * period)
        s.step()
        sender.close()
        flags = s.episode.buf.arrays["step_flags"][:4]
        # wrists only: the hands hold home (NO_INPUT_YET); only the empty step is a drop
        assert [int(f) & ~StepFlag.NO_INPUT_YET for f in flags] == [0, 0, StepFlag.DROPPED, 0]
        assert all(f & StepFlag.NO_INPUT_YET for f in flags)
        assert "no new frame for 16.7 ms" in s.episode.buf.notes[2]
    finally:
        source.close()


def test_a_failed_write_keeps_the_episode_for_another_save(stream_path, tmp_path):
    blocked = tmp_path / "out"
    blocked.write_text("a file where the output folder should be")
    s = session(stream_path, blocked)
    s.handle("start")
    for _ in range(5):
        s.step()
    ok, msg = s.handle("save")
    assert not ok and "could not write" in msg and s.episode is not None
    blocked.unlink()
    assert s.handle("save")[0] and read_raw(blocked / "episode_0000.raw.h5").num_steps == 5
