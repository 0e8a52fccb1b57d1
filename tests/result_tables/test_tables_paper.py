"""The records contract reproduces a published benchmark: the paper's own Table 2 counts, written by
hand as records, give the paper's aggregates (macro row, Full/None ratios, task comparisons, leaders)."""

import json

import pytest
from tables_records import cells_from_counts, paper_table, records_from_counts

from result_tables import build_tables
from result_tables.aggregate import aggregate
from result_tables.provenance import provenance
from result_tables.text import latex, markdown

POLICIES = ("ACT", "DP", "pi0.5", "GR00T N1.5")
# paper, "Task mean (%)" row and section "Generalization Patterns"
MACRO = {"ACT": (29.5, 15.4, 14.0, 13.0, 18.0, 33.5), "DP": (12.9, 6.3, 5.2, 3.8, 7.1, 23.0),
         "pi0.5": (27.3, 13.2, 21.0, 19.7, 20.3, 36.1), "GR00T N1.5": (48.5, 18.8, 26.0, 19.8, 28.3, 47.3)}
FULL_NONE = {"ACT": 44.1, "DP": 29.8, "pi0.5": 72.1, "GR00T N1.5": 40.9}
FULL_VS_NONE = {"ACT": (25, 1, 0), "DP": (20, 6, 0), "pi0.5": (18, 8, 0), "GR00T N1.5": (26, 0, 0)}
INV_VS_EQUI = {"ACT": (6, 9, 11), "DP": (7, 10, 9), "pi0.5": (18, 5, 3), "GR00T N1.5": (16, 3, 7)}
SUCCESSES = {"none": {"GR00T N1.5": 631, "ACT": 383, "pi0.5": 355, "DP": 168},
             "inv_equi": {"GR00T N1.5": 258, "pi0.5": 256, "ACT": 169, "DP": 50}}


@pytest.fixture(scope="module")
def paper_summary():
    cells = cells_from_counts(paper_table())
    return {"metadata": provenance(cells, [], 200, 0), **aggregate(cells, n_boot=200, seed=0)}


def test_the_paper_table_gives_the_papers_aggregates(paper_summary):
    s = {p["policy"]: p for p in paper_summary["policy_summaries"]}
    assert set(s) == set(POLICIES) and len(paper_summary["tasks"]) == 26
    for policy, (none, equi, inv, full, sr, lscr) in MACRO.items():
        by = s[policy]["by_channel"]
        got = [by[c]["SR"] for c in ("none", "equi_only", "inv_only", "inv_equi")] + [s[policy]["SR"], s[policy]["LSCR"]]
        assert [round(100 * v, 1) for v in got] == [none, equi, inv, full, sr, lscr], policy
        assert round(100 * s[policy]["full_none_ratio"], 1) == FULL_NONE[policy]
        fn, ie = s[policy]["full_vs_none"], s[policy]["inv_vs_equi"]
        assert (fn["below"], fn["equal"], fn["above"]) == FULL_VS_NONE[policy]
        assert (ie["higher"], ie["equal"], ie["lower"]) == INV_VS_EQUI[policy]
        assert all(by[c]["episodes"] == 1300 and by[c]["n_tasks"] == 26 for c in by)
    for channel, counts in SUCCESSES.items():
        assert {p: s[p]["by_channel"][channel]["successes"] for p in POLICIES} == counts
    # "89 of the 104 task-policy comparisons" lower under Full, "the remaining 15 are tied"
    assert sum(s[p]["full_vs_none"]["below"] for p in POLICIES) == 89
    assert sum(s[p]["full_vs_none"]["equal"] for p in POLICIES) == 15


def test_task_level_leaders_match_the_paper(paper_summary):
    none, full = paper_summary["leads"]["none"], paper_summary["leads"]["inv_equi"]
    # None: GR00T leads 23 of 26, pi0.5 two, ACT ties GR00T on the remaining one
    assert none["strict_leads"] == {"ACT": 0, "DP": 0, "GR00T N1.5": 23, "pi0.5": 2} and none["ties"] == 1
    # Full: pi0.5 12 strict leads, GR00T eight, ACT two, four ties
    assert full["strict_leads"] == {"ACT": 2, "DP": 0, "GR00T N1.5": 8, "pi0.5": 12} and full["ties"] == 4


def test_rows_and_renderings_follow_table_2(paper_summary):
    rows = {(r["task"], r["policy"]): r for r in paper_summary["rows"]}
    assert round(100 * rows[("Microwave Bowl Loading", "ACT")]["SR"], 1) == 62.5
    assert rows[("Microwave Bowl Loading", "ACT")]["channels"]["inv_equi"]["n_success"] == 29
    tex = latex(paper_summary)
    assert r"Screwdriver Box \& Hammer" in tex and r"\toprule" in tex and r"\bottomrule" in tex
    assert r"\multirow[c]{3}{*}{IIWA7+Sharpa}" in tex
    assert r"\textbf{59.5\%} & \textbf{72.2\%}" in tex      # GR00T's best SR and LSCR on Gaming Desk Setup
    assert r"29.5\% & 15.4\% & 14.0\% & 13.0\% & 18.0\% & 33.5\%" in tex   # ACT's task-mean row
    md = markdown(paper_summary)
    assert "| Gaming Desk Setup | JAKA ZU7+DexHand021 | 25 | 10 | 17 | 10 | 31.0% | 46.0% |" in md


def test_hand_written_records_file_goes_through_end_to_end(tmp_path):
    """Three published rows of two policies written as a CSV in the contract's minimum columns (with the
    paper's channel labels): the per-row numbers are the paper's, the macro numbers the hand-computed ones."""
    table = paper_table()
    table = table[(table["embodiment"] == "IIWA7+Sharpa") & table["policy"].isin(["ACT", "pi0.5"])]
    labels = {"none": "None", "equi_only": "Equi.", "inv_only": "Inv.", "inv_equi": "Full"}
    records = records_from_counts(table, channel_names=labels)
    assert list(records.columns) == ["task", "embodiment", "policy", "channel", "episode", "success", "lscr"]
    path = tmp_path / "other_benchmark.csv"
    records.to_csv(path, index=False)
    summary, _ = build_tables([path], tmp_path / "out", n_boot=500)
    assert json.loads((tmp_path / "out" / "summary.json").read_text()) is not None
    for r in summary["rows"]:
        published = table[(table.task == r["task"]) & (table.policy == r["policy"])].iloc[0]
        assert round(100 * r["SR"], 1) == published.sr_percent
        assert r["LSCR"] == pytest.approx(published.lscr_percent / 100)
        assert r["channels"]["none"]["n_success"] == published.none
    s = {p["policy"]: p for p in summary["policy_summaries"]}
    act, pi = s["ACT"], s["pi0.5"]
    assert act["by_channel"]["none"]["SR"] == pytest.approx(26 / 150)          # (9 + 17 + 0) / 150
    assert act["SR"] == pytest.approx(31 / 600)                                # 26 + 4 + 1 + 0 successes
    assert act["LSCR"] == pytest.approx((0.116 + 0.346 + 0.125) / 3)
    assert act["full_none_ratio"] == 0.0
    assert act["full_vs_none"] == {"below": 2, "equal": 1, "above": 0}
    assert act["inv_vs_equi"] == {"higher": 0, "equal": 1, "lower": 2}
    assert pi["full_none_ratio"] == pytest.approx(11 / 14)                     # (4 + 7 + 0) / (7 + 7 + 0)
    assert pi["full_vs_none"] == {"below": 1, "equal": 2, "above": 0}
    assert pi["inv_vs_equi"] == {"higher": 2, "equal": 1, "lower": 0}
    for p in s.values():
        lo, hi = p["SR_ci"]
        assert lo <= p["SR"] <= hi
    assert summary["metadata"]["N_per_cell"] == {"min": 50, "max": 50, "cells": 24, "episodes": 1200}


def test_a_missing_cell_is_listed_and_its_row_averages_the_channels_present(paper_summary):
    assert paper_summary["missing_cells"] == []
    cells = cells_from_counts(paper_table())
    gone = (cells["task"] == "Soup Serving") & (cells["policy"] == "ACT") & (cells["channel"] == "inv_equi")
    summary = aggregate(cells[~gone], n_boot=100, seed=0)
    assert summary["missing_cells"] == [["Soup Serving", "UR5+Shadow", "ACT", "inv_equi"]]
    row = next(r for r in summary["rows"] if r["task"] == "Soup Serving" and r["policy"] == "ACT")
    assert row["channels"]["inv_equi"] is None and row["SR"] == pytest.approx((2 + 0 + 0) / 150)
    act = next(s for s in summary["policy_summaries"] if s["policy"] == "ACT")
    assert act["by_channel"]["inv_equi"]["n_tasks"] == 25
