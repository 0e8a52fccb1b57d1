"""RGB-D and tactile renders of each replay under the active sensor profile: a graph-backed asset that
renders each replay in its own step (b2d_pipeline/ops/render_replays.py)."""


import dagster as dg

from b2d_pipeline.ops.render_replays import build_render_graph
from b2d_pipeline.partitions import settings_partitions
from b2d_pipeline.schedules import RERENDER_ON_PROFILE_CHANGE
from b2d_pipeline.settings import FactorySettings


def build(settings: FactorySettings):
    profile = settings.profile
    # The profile hash in the code version: a changed profile marks renders (and downstream) stale.
    # 2: renders carry the tactile frames (robot/tactile) when the profile enables them.
    # 3: labels (segmentation, 2D/3D boxes, occupancy) as the profile lists them.
    return dg.graph_asset(
        build_render_graph(profile, settings.render_workers), name="renders",
        ins={"replays": dg.AssetIn("replays", dagster_type=dg.Nothing)},
        partitions_def=settings_partitions, group_name="renders", code_version=f"3-{profile.content_hash}",
        automation_condition=RERENDER_ON_PROFILE_CHANGE,
        description=f"Camera and tactile renders under the '{profile.name}' sensor profile "
                    f"({profile.content_hash}), one step per replay.")
