"""The `press` step kind's schema."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, ValidationInfo, field_validator

from ..base import Name
from .fields import plan_scope
from .step import PlanStep


class PressStep(PlanStep):
    """{hand, press: [<object>/<link>, ...], [after], [wait_s]}: press these slide-jointed links (keys,
    buttons) in order."""

    press: Annotated[list[Name], Field(min_length=1)]

    @field_validator("press", mode="before")
    @classmethod
    def _keys(cls, press, info: ValidationInfo):
        keys = sorted(f"{n}/{link.name}" for n, o in plan_scope(info).objects.items() for link in o.links
                      if link.joint.type == "slide")
        if not isinstance(press, list) or not press or not all(isinstance(k, str) and k in keys for k in press):
            raise ValueError(f"a non-empty list of slide-jointed links from {keys}")
        return press
