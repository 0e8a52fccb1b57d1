"""Declarative arm / hand / embodiment descriptions: the public names, gathered from the modules that own them.

Catalog layout (``sim/catalog``): ``arms/<name>.yaml``, ``hands/<name>.yaml``, ``embodiments/<name>.yaml``.
Every file is plain data, read with ``yaml.safe_load`` and checked by its schema (``sim/schema``: unknown
keys, wrong types and out-of-range values refused, file and field named); the loaders then check what
crosses fields (joint names, links, actuators) and build the dataclasses. The builder in ``builder.py``
turns descriptions into MuJoCo bodies and ``kinematics.py`` into a Pinocchio model.

    frames.py          rotations and rigid transforms
    fields.py          DescriptionError and the field path of cross-reference errors
    catalog_paths.py   where the files are; reading one through its schema
    links.py           geoms, joints, mass properties -> LinkSpec
    tactile_block.py   a hand's tactile pads and site registry (its schema: sim/schema/tactile.py)
    arm_file.py, hand_file.py, embodiment_file.py   one loader per kind

Conventions (all lengths in metres, angles in radians): arm joints follow URDF (``arm_file.py``); hands
are described for the RIGHT side and mirrored for the left (``hand_file.py``, ``mirror.py``).
"""

from __future__ import annotations

from sim.schema.embodiment import CAMERA_NAMES

from .arm_file import KEEP_SIGN_MARGIN_RAD, ArmDescription, arm_names, load_arm
from .catalog_paths import ARMS_DIR, CATALOG_DIR, EMBODIMENTS_DIR, HANDS_DIR
from .embodiment_file import DEFAULT_FOVY, CameraSpec, EmbodimentDescription, embodiment_names, load_embodiment
from .fields import DescriptionError, _Ctx, _expected_error
from .frames import (Transform, frame_from_axes, frame_transform, mat_to_quat, quat_to_mat,
                     rpy_to_matrix)
from .hand_file import (ActuatorSpec, CouplingSpec, GraspProbe, HandDescription, TabletopGrasp, coupled_position,
                        coupled_slope, hand_names, load_hand, read_hand_file)
from .links import GEOM_TYPES, GeomSpec, Inertial, JointSpec, LinkSpec
from .tactile_block import (PAD_FIELDS, PAD_SYMMETRY_TOLERANCE_M, TACTILE_SIDES, THUMB, TactileGroup, TactilePad,
                            TactileSite, TactileSpec, parse_tactile_block, parse_tactile_pad)

__all__ = [
    "ARMS_DIR", "CAMERA_NAMES", "CATALOG_DIR", "DEFAULT_FOVY", "EMBODIMENTS_DIR", "GEOM_TYPES", "HANDS_DIR",
    "KEEP_SIGN_MARGIN_RAD", "PAD_FIELDS", "PAD_SYMMETRY_TOLERANCE_M", "TACTILE_SIDES", "THUMB",
    "ActuatorSpec", "ArmDescription", "CameraSpec", "CouplingSpec", "DescriptionError", "EmbodimentDescription",
    "GeomSpec", "GraspProbe", "HandDescription", "Inertial", "JointSpec", "LinkSpec", "TabletopGrasp",
    "TactileGroup", "TactilePad", "TactileSite", "TactileSpec", "Transform",
    "arm_names", "coupled_position", "coupled_slope", "embodiment_names", "frame_from_axes", "frame_transform",
    "hand_names", "load_arm", "load_embodiment", "load_hand", "mat_to_quat", "parse_tactile_block",
    "parse_tactile_pad", "quat_to_mat", "read_hand_file", "rpy_to_matrix",
    "_Ctx", "_expected_error",
]
