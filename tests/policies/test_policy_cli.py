"""`b2d train` and `b2d eval` from the command line: a checkpoint from real episodes, its evaluation anchored on
its own training scenes, and clear one-line errors for bad input."""

import json

from click.testing import CliRunner

from b2d_cli.main import cli

SETTING = "citrus_plate_loading__ur5_rh5dg2"


def test_train_then_eval_anchored_on_the_training_scenes(policy_episodes, tmp_path):
    runner = CliRunner()
    out = tmp_path / "ckpt"
    trained = runner.invoke(cli, ["train", "--setting", SETTING, "--policy", "act", "--out", str(out),
                                  "--episodes", str(policy_episodes[0].parent), "--steps", "2"])
    assert trained.exit_code == 0, trained.output
    summary = json.loads(trained.stdout[trained.stdout.index("{"):])
    assert summary["steps"] == 2 and summary["episodes"] == len(policy_episodes)
    records = tmp_path / "records.parquet"
    evaluated = runner.invoke(cli, ["eval", "--checkpoint", str(out), "--channel", "none", "--episodes", "2",
                                    "--max-steps", "6", "--json", "--out", str(records)])
    assert evaluated.exit_code == 0, evaluated.output
    cells = json.loads(evaluated.stdout[evaluated.stdout.index("["):])
    assert [(c["channel"], c["N"]) for c in cells] == [("none", 2)]
    import pandas as pd
    rows = pd.read_parquet(records)
    assert list(rows["anchor"]) == [p.stem for p in sorted(policy_episodes)][:2]
    # provenance for `b2d tables`: the checkpoint's sensor profile and the horizon rule with its cap
    assert set(rows["sensor_profile_hash"]) == {json.loads((out / "policy.json").read_text())["profile_hash"]}
    assert rows["horizon_rule"].str.endswith("capped at 6").all()


def test_bad_input_is_one_line_naming_what_is_wrong(tmp_path):
    runner = CliRunner()
    missing = runner.invoke(cli, ["eval", "--checkpoint", str(tmp_path / "nowhere")])
    assert missing.exit_code == 2 and "checkpoint folder" in missing.output
    (tmp_path / "empty").mkdir()
    empty = runner.invoke(cli, ["train", "--setting", SETTING, "--policy", "act", "--out", str(tmp_path / "c"),
                                "--episodes", str(tmp_path / "empty")])
    assert empty.exit_code == 2 and "no episodes of" in empty.output
    unknown = runner.invoke(cli, ["train", "--setting", SETTING, "--policy", "act", "--config", "huge",
                                  "--out", str(tmp_path / "c")])
    assert unknown.exit_code == 2 and "valid act config names: paper, tiny, tiny_tactile" in unknown.output
