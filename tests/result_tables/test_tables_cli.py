"""`b2d tables` end to end on a small records file: every output, the same bytes twice, bad input refused."""

import base64
import json
import re

import pandas as pd
from click.testing import CliRunner
from tables_records import paper_table, records_from_counts

from b2d_cli.main import cli
from result_tables import OUTPUTS


def small_records(tmp_path):
    """Two settings x two policies x four channels x 6 episodes, with seeds and provenance columns."""
    table = paper_table()
    table = table[table["task"].isin(["Gaming Desk Setup", "Microwave Bowl Loading"]) & table["policy"].isin(["ACT", "DP"])]
    table = table.assign(**{c: (table[c] * 6 // 50) for c in ("none", "equi", "inv", "full")})
    df = records_from_counts(table, n=6)
    df["seed"] = range(1000, 1000 + len(df))
    df["termination"] = ["stable_success" if s else "horizon" for s in df["success"]]
    df.loc[5, ["termination", "success", "lscr"]] = ["error", None, None]       # one episode ended in error
    df["sensor_profile_hash"] = "abc123"
    path = tmp_path / "records.parquet"
    df.to_parquet(path)
    return path


def test_tables_end_to_end(tmp_path):
    path = small_records(tmp_path)
    runner = CliRunner()
    out_a = tmp_path / "a"
    res = runner.invoke(cli, ["tables", "--records", str(path), "--out", str(out_a), "--resamples", "500",
                              "--horizon-rule", "1.5x expert"])
    assert res.exit_code == 0, res.output
    assert "4 rows, 16 cells, 96 episodes" in res.output
    assert sorted(p.name for p in out_a.iterdir()) == sorted(OUTPUTS)
    summary = json.loads((out_a / "summary.json").read_text())
    meta = summary["metadata"]
    assert meta["sensor_profile_hash"] == ["abc123"] and meta["horizon_rule"] == ["1.5x expert"]
    assert meta["seeds"]["episode_seed_range"] == [1000, 1095] and meta["seeds"]["bootstrap"]["resamples"] == 500
    assert meta["N_per_cell"] == {"min": 6, "max": 6, "cells": 16, "episodes": 96}
    assert meta["evaluation_failures"] == 1 and meta["code_version"]
    assert meta["records"][0]["sha256"]
    for name in ("tables.md", "tables.tex", "index.html"):     # the metadata is on every text output
        text = (out_a / name).read_text()
        assert "abc123" in text and "1.5x expert" in text and meta["code_version"] in text
    html = (out_a / "index.html").read_text()
    images = re.findall(r'src="data:image/png;base64,([A-Za-z0-9+/=]+)"', html)
    assert len(images) == 3 and all(base64.b64decode(i).startswith(b"\x89PNG") for i in images)
    assert "<script" not in html and "http" not in html.replace("http-equiv", "")
    for name in ("sr_per_channel.png", "rr_heatmap.png", "sr_vs_lscr.png"):
        png = (out_a / name).read_bytes()
        assert png.startswith(b"\x89PNG") and b"abc123" in png and b"1.5x expert" in png   # metadata text chunk
    # the same records and options: the same bytes (no timestamps anywhere); an earlier output is replaced
    before = {n: (out_a / n).read_bytes() for n in OUTPUTS}
    res = runner.invoke(cli, ["tables", "--records", str(path), "--out", str(out_a), "--resamples", "500",
                              "--horizon-rule", "1.5x expert"])
    assert res.exit_code == 0, res.output
    assert all((out_a / n).read_bytes() == before[n] for n in OUTPUTS)
    # a folder that is not an earlier output is left alone
    other = tmp_path / "mine"
    other.mkdir()
    (other / "notes.txt").write_text("keep")
    res = runner.invoke(cli, ["tables", "--records", str(path), "--out", str(other), "--resamples", "500"])
    assert res.exit_code != 0 and "not an earlier `b2d tables` output" in res.output
    assert (other / "notes.txt").read_text() == "keep"


def test_tables_refuses_bad_records(tmp_path):
    good = small_records(tmp_path)
    bad = tmp_path / "bad.csv"
    pd.read_parquet(good).assign(channel="sideways").to_csv(bad, index=False)
    res = CliRunner().invoke(cli, ["tables", "--records", str(good), str(bad), "--out", str(tmp_path / "out")])
    assert res.exit_code == 1
    assert f"{bad}: column 'channel': unknown channel ['sideways']" in res.output and "rows 0, 1, 2" in res.output
    assert not (tmp_path / "out").exists()
