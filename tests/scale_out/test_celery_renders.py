"""A real partition of the factory on two Celery workers: one setting's `renders` (a graph-backed asset, one
`render_replay` step per replay) materialised through the celery executor, with Redis as broker and the
instance on PostgreSQL. Both workers render, and the files are byte for byte those of an in-process run on
the same replays (two short demonstrations, the small policy_tiny profile)."""

from __future__ import annotations

import shutil
from pathlib import Path

import dagster as dg
import pytest

from b2d_pipeline.chain import reconstructable_job
from b2d_pipeline.definitions import build_definitions
from b2d_pipeline.resources import EpisodeStore
from b2d_pipeline.settings import FactorySettings
from episodes.stages import replay_to_file
from foundation_demos import SETTING
from loopback_services import CELERY_PROFILE, celery_worker_of_steps
from sim.registry import sensor_profile

pytest.importorskip("dagster_celery", reason="dagster-celery is not installed (pip install -e '.[scale]')")


def _write_replays(raw_dir: Path, data_root: Path) -> list[str]:
    folder = EpisodeStore(data_root=str(data_root)).replay_dir(SETTING)
    folder.mkdir(parents=True, exist_ok=True)
    for raw in sorted(raw_dir.glob("*.raw.h5")):
        replay_to_file(raw, folder / raw.name.replace(".raw.h5", ".replay.h5"))
    return sorted(p.name for p in folder.glob("*.replay.h5"))


def _renders(data_root: Path, profile_hash: str) -> dict[str, bytes]:
    folder = EpisodeStore(data_root=str(data_root)).render_dir(profile_hash, SETTING)
    return {p.name: p.read_bytes() for p in sorted(folder.glob("*.render.h5"))}


def test_a_settings_renders_run_on_two_celery_workers_with_the_in_process_bytes(celery_run, raw_dir, tmp_path,
                                                                                 monkeypatch):
    workers, home, run_env = celery_run
    celery_root = Path(run_env["B2D_DATA_ROOT"])
    replays = _write_replays(raw_dir, celery_root)
    assert replays == ["episode_0000.replay.h5", "episode_0001.replay.h5"]

    # the reference: the same replays rendered in this process
    local_root = tmp_path / "in_process"
    shutil.copytree(celery_root / "replays", local_root / "replays")
    local = build_definitions(FactorySettings.from_env(data_root=local_root, profile=CELERY_PROFILE, executor="in_process"))
    with dg.DagsterInstance.ephemeral() as ephemeral:
        reference = dg.materialize(list(local.assets), selection=["renders"], partition_key=SETTING,
                                   resources=local.resources, instance=ephemeral)
        assert reference.success

    for name, value in run_env.items():       # the run's own process rebuilds the job and submits its steps
        monkeypatch.setenv(name, value)
    with dg.DagsterInstance.from_config(str(home)) as instance:
        # `b2d materialize`'s own job (b2d_pipeline/chain.py), its renders only
        result = dg.execute_job(reconstructable_job("produce_and_train", FactorySettings.from_env()), instance,
                                asset_selection=[dg.AssetKey("renders")], tags={"dagster/partition": SETTING})
        assert result.success
        worker_of = celery_worker_of_steps(instance.all_logs(result.run_id))
        assert SETTING in instance.get_materialized_partitions(dg.AssetKey("renders"))

    render_steps = {f"renders.render_replay[{name.removesuffix('.replay.h5')}]" for name in replays}
    assert set(worker_of) == {"renders.list_replays", "renders.gather_renders", *render_steps}
    assert {worker_of[step] for step in render_steps} == set(workers)      # one replay on each worker

    profile_hash = sensor_profile(CELERY_PROFILE).content_hash
    on_workers, in_process = _renders(celery_root, profile_hash), _renders(local_root, profile_hash)
    assert sorted(in_process) == ["episode_0000.render.h5", "episode_0001.render.h5"]
    assert on_workers == in_process
