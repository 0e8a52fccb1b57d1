import json

from tactile.bench import run_tactile_bench


def test_bench_runs_small_and_returns_json_figures():
    result = run_tactile_bench(resolution=48, sites=3)
    json.dumps(result)
    assert result["grasp_sites_in_contact"] == 3 and result["grasp_contact_cells"] > 0
    assert result["no_contact_rays_cast"] == 0  # the broad phase rejected every site
    assert result["rays_per_s_per_core"] > 0 and result["mj_ray_rays_per_s"] > 0
    assert result["mj_ray_hit_agreement"] == 1.0 and result["mj_ray_max_depth_diff_m"] < 1e-6
    assert "extrapolated" in result["mj_ray_note"]
