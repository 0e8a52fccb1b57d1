"""`b2d bench policy` runs end to end at the smallest size and reports every figure it promises."""

from policies.bench import run_policy_bench


def test_policy_bench_reports_training_inference_throughput_memory_and_shares():
    figures = run_policy_bench("act", "tiny", demos=1, demo_steps=30, train_steps=2, eval_episodes=1, max_steps=9,
                               queries=2)
    assert figures["training"]["steps"] == 2 and figures["training"]["steps_per_second"] > 0
    evaluation = figures["evaluation"]
    assert evaluation["control_steps_per_episode"] == 9 and evaluation["queries_per_episode"] == 3
    assert set(evaluation["share"]) == {"render", "policy", "physics", "evaluate", "other"}
    assert abs(sum(evaluation["share"].values()) - 1.0) < 1e-9
    assert evaluation["inference_ms_per_query"]["median"] > 0
    # the views were rendered on the timed thread: CPU time, at most the wall time it took
    assert 0 < evaluation["render_cpu_ms_per_policy_step"] <= evaluation["ms_per_policy_step"]["render"] * 1.05
    assert figures["training"]["peak_rss_mb"] > 100 and evaluation["peak_rss_mb"] > 100
    assert figures["baseline_scripted_operator"]["queries_per_episode"] == 9     # queried every control step
    assert figures["evaluation_vs_baseline"] > 0
