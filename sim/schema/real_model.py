"""Schema of a hand file's `real_model` block: where the real MJCF of the hand is and how its names and
frames map onto the generated hand (sim/embodiment/real_model.py says what each field does). What it
names of the hand (every joint once, one entry per actuator, the bodies tactile pads attach to) is checked
against the hand by sim/embodiment/real_model_file.py.
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field, model_validator

from .base import CatalogModel, Name, PositiveNumber, Str
from .robot_parts import Frame, PerSide


class RealActuator(CatalogModel):
    """Our actuator a model actuator drives (`A_FFJ0: FFJ2`, or `{name: FFJ2, ctrl_scale: 0.5}` where our
    target is a fraction of the model's: a tendon servo driving two joints)."""

    keys_label: ClassVar[str] = "an actuator key"

    name: Name
    ctrl_scale: PositiveNumber = 1.0

    @model_validator(mode="before")
    @classmethod
    def _a_name_alone(cls, raw):
        return {"name": raw} if isinstance(raw, str) else raw


class RealModel(CatalogModel):
    keys_label: ClassVar[str] = "a real_model key"

    source: Str
    menagerie: Name = None                  # a MuJoCo Menagerie folder, found under $MENAGERIE_ROOT
    files: PerSide[Name] = None             # ... and the files in it
    mjcf: PerSide[Name] = None              # or the files themselves, relative to the hand file
    name_prefix: PerSide[Str] = None        # each side's prefix of the model's names (empty: none)
    root_body: Name
    mount: PerSide[Frame]
    link_frame: Frame = None
    drop_joints: list[Name] = []
    joints: dict[str, Name] = Field(min_length=1, description="a mapping of model joint -> our joint")
    actuators: dict[str, RealActuator] = Field(min_length=1, description="a mapping of model actuator -> ours")
    bodies: dict[str, Name] = Field(min_length=1, description="a mapping of our link -> model body")

    @model_validator(mode="after")
    def _found_somewhere(self):
        if not ((self.menagerie and self.files) or self.mjcf):
            raise ValueError("'menagerie' + 'files: {right, left}' and/or 'mjcf: {right, left}'")
        return self
