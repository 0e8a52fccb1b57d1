"""Issue 23, item 5: temporaries of killed runs are cleaned at the next start; render workers die with
their parent; a full disk is a clear error, not a crash.

A full disk is simulated with a file-size limit (RLIMIT_FSIZE) in a subprocess: writes past it fail with
EFBIG as a full disk fails with ENOSPC, and no root is needed to mount a tiny tmpfs. (With root, a 48 KB
tmpfs gave the same messages and exit codes by hand.)"""

import os
import resource
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from episodes.atomic import clean_stale_temporaries

ENV = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}


def _dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_temporaries_of_dead_processes_go_and_live_ones_stay(tmp_path):
    dead, live = _dead_pid(), os.getpid()
    stale = [tmp_path / f".episode_0000.hdf5.tmp-{dead}", tmp_path / f".episode_0001.old-{dead}",
             tmp_path / f".clip.tmp-{dead}.mp4", tmp_path / f".render-parts-{dead}-k2x_9a"]
    kept = [tmp_path / f".episode_0002.hdf5.tmp-{live}", tmp_path / "episode_0000.hdf5", tmp_path / ".work",
            tmp_path / "notes.tmp-12"]
    for path in stale + kept:
        if path.name.startswith(".render-parts") or path.name == ".work":
            path.mkdir()
            (path / "part000.render.h5").write_bytes(b"x")
        else:
            path.write_bytes(b"x")
    assert sorted(clean_stale_temporaries(tmp_path)) == sorted(p.resolve() for p in stale)
    assert sorted(tmp_path.iterdir()) == sorted(kept)


PARENT = textwrap.dedent("""
    import os, sys, time
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor
    from episodes.workers import die_with_parent

    def work(_):
        time.sleep(120)

    if __name__ == "__main__":
        pool = ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=die_with_parent, initargs=(os.getpid(),))
        futures = [pool.submit(work, i) for i in range(2)]
        time.sleep(0.5)
        print(" ".join(str(p) for p in pool._processes), flush=True)
        time.sleep(120)
""")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    # a zombie is dead: its parent (here the killed one's reaper) has not collected it yet
    stat = Path(f"/proc/{pid}/stat")
    return not (stat.exists() and stat.read_text().rsplit(")", 1)[1].split()[0] == "Z")


def test_workers_die_with_their_parent(tmp_path):
    script = tmp_path / "parent.py"
    script.write_text(PARENT)
    parent = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                              cwd=Path(__file__).parents[2], env={**ENV, "PYTHONPATH": str(Path(__file__).parents[2])})
    workers = [int(p) for p in parent.stdout.readline().split()]
    assert len(workers) == 2 and all(_alive(p) for p in workers)
    parent.send_signal(signal.SIGKILL)
    parent.wait()
    deadline = time.monotonic() + 10
    while any(_alive(p) for p in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_alive(p) for p in workers), "render workers outlived their parent"


def _limited(size_bytes: int):
    def limit():
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)     # else the kernel kills the writer outright
        resource.setrlimit(resource.RLIMIT_FSIZE, (size_bytes, size_bytes))
    return limit


def _b2d(args, limit_bytes, cwd):
    return subprocess.run([sys.executable, "-c", "from b2d_cli.main import cli; cli()", *map(str, args)],
                          capture_output=True, text=True, preexec_fn=_limited(limit_bytes), env=ENV, cwd=cwd,
                          timeout=300)


def test_record_on_a_full_disk_is_a_clear_error(tmp_path):
    out = tmp_path / "raw"
    result = _b2d(["record", "--task", "citrus_plate_loading", "--embodiment", "ur5_rh5dg2", "--out", out,
                   "--max-steps", "6"], 4096, Path(__file__).parents[2])
    assert result.returncode == 1, result.stderr[-2000:]
    assert f"0000  steps=0     error: OSError: [Errno 27] File too large: '{out / 'episode_0000.raw.h5'}'" in result.stdout
    assert "1 of 1 episodes failed: 0000" in result.stderr
    assert list(out.iterdir()) == []                          # no temporary left behind


def test_replay_on_a_full_disk_is_a_clear_error_not_a_crash(raw_path, tmp_path):
    out = tmp_path / "episodes"
    result = _b2d(["replay", raw_path, "--profile", "preview", "--out", out, "--max-frames", "1"], 60_000,
                  Path(__file__).parents[2])
    assert result.returncode == 1, result.stderr[-2000:]      # a segmentation fault before (-11)
    lines = [line for line in result.stderr.splitlines() if line.startswith("error: ")]
    assert lines and lines[0].startswith(f"error: {raw_path}: no space left writing {out}"), result.stderr[-2000:]
    assert not [p for p in out.rglob("*") if ".tmp-" in p.name]
