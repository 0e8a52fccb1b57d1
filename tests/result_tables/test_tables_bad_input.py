"""Bad records are refused with a message naming the file, the column and the rows; every problem of
every file is listed at once."""

import pandas as pd
import pytest

from result_tables import RecordsError
from result_tables.load import load_records


def episodes(n=4, **over) -> pd.DataFrame:
    df = pd.DataFrame({"task": "t1", "embodiment": "e1", "policy": "p1", "channel": "none",
                       "episode": range(n), "success": [1, 0] * (n // 2), "lscr": 0.5})
    return df.assign(**over)


def refused(*paths) -> RecordsError:
    with pytest.raises(RecordsError) as info:
        load_records(paths)
    return info.value


def test_missing_column_names_file_and_column(tmp_path):
    path = tmp_path / "no_success.csv"
    episodes().drop(columns=["success"]).to_csv(path, index=False)
    err = refused(path)
    assert str(path) in str(err) and "column 'success': missing" in str(err)
    assert err.problems == [(str(path), "success", err.problems[0][2], [])]


def test_unknown_channel_names_file_column_rows_and_valid_names(tmp_path):
    df = episodes(6)
    df.loc[[1, 4], "channel"] = "Fulll"
    path = tmp_path / "typo.parquet"
    df.to_parquet(path)
    msg = str(refused(path))
    assert f"{path}: column 'channel': unknown channel ['Fulll']" in msg
    assert "(rows 1, 4)" in msg and "inv_equi" in msg and "'Full'" in msg


def test_duplicate_episode_ids_in_one_file_and_across_files(tmp_path):
    df = episodes(4)
    df.loc[3, "episode"] = 1
    one = tmp_path / "dup.csv"
    df.to_csv(one, index=False)
    msg = str(refused(one))
    assert f"{one}: column 'episode': duplicate episode ids" in msg and "(rows 1, 3)" in msg
    a, b = tmp_path / "a.csv", tmp_path / "b.parquet"
    episodes(4).to_csv(a, index=False)
    episodes(4).iloc[2:].to_parquet(b)          # episodes 2 and 3 again, in another file
    err = refused(a, b)
    assert {(p[0], p[1], tuple(p[3])) for p in err.problems} == {(str(a), "episode", (2, 3)),
                                                                 (str(b), "episode", (0, 1))}
    assert str(b) in err.problems[0][2]          # each names the other file


def test_every_problem_of_every_file_is_listed(tmp_path):
    bad = episodes(4, success=["yes", "maybe", 0, 2], lscr=[0.5, 1.5, "x", 0.0])
    bad.loc[0, "task"] = ""
    p1, p2 = tmp_path / "bad.csv", tmp_path / "notes.txt"
    bad.to_csv(p1, index=False)
    p2.write_text("nothing")
    err = refused(p1, p2, tmp_path / "missing.parquet")
    found = {(p[1], tuple(p[3])) for p in err.problems if p[0] == str(p1)}
    assert found == {("task", (0,)), ("success", (1, 3)), ("lscr", (2,)), ("lscr", (1,))}
    msg = str(err)
    assert f"{p2}: column '-': expected a .parquet or .csv records file" in msg
    assert "missing.parquet: column '-': no such file" in msg


def test_error_episode_may_leave_success_empty_but_others_may_not(tmp_path):
    df = episodes(4, termination=["stable_success", "horizon", "error", "horizon"])
    df["success"] = df["success"].astype(object)
    df.loc[[2, 3], "success"] = None
    path = tmp_path / "errors.parquet"
    df.to_parquet(path)
    err = refused(path)
    assert [(p[1], p[3]) for p in err.problems] == [("success", [3])]


def test_an_empty_file_or_folder_is_refused(tmp_path):
    empty = tmp_path / "empty.csv"
    episodes().iloc[:0].to_csv(empty, index=False)
    assert f"{empty}: column '-': no episode rows" in str(refused(empty))
    (tmp_path / "nothing").mkdir()
    assert "no .parquet or .csv records files found" in str(refused(tmp_path / "nothing"))
