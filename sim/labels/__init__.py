"""Ground-truth labels of a posed scene: segmentation, 2D and 3D boxes, occupancy.

Plain functions and small classes over a compiled ``mujoco.MjModel``, a posed ``MjData`` and (for the
image labels) MuJoCo's segmentation render; no HDF5, no Dagster. Every label is a deterministic
function of those inputs, with stable ids (`ids.LabelIds`): instance ids follow the task's object
list, so two runs give identical ids.

    ids.py           which task object / robot part / table each geom belongs to; semantic classes
    segmentation.py  render MuJoCo's (objid, objtype) image and map it to semantic / instance masks
    box2d.py         per camera and object: visible-pixel box (xyxy) and a visibility fraction
    box3d.py         per object: oriented world box (centre, size l/w/h, quaternion)
    occupancy.py     voxel grid of the workspace with a semantic (and instance) label per voxel
    geometry.py      per-geom bounds, point containment and surface samples (primitives and meshes)
    bench.py         ms per frame of each label against the RGB render of the same cameras
"""
