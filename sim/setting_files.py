"""The catalog files that shape one setting's demonstrations, and a hash of their content.

A setting (task x embodiment) is built from four YAML files: the task (objects, stages, its
demonstration plan), the embodiment, and the arm and hand it names. Editing any of them changes what
the scripted operator records, so the pipeline keys the setting's recordings on this hash: an edited
task marks that setting's recordings stale, and no other setting's.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from sim import registry


def setting_source_files(task: str, embodiment: str) -> dict[str, Path]:
    """{role: path} of the files that define the setting; unknown names fail fast, listing valid ones."""
    embodiment_path = registry.catalog_path("embodiments", embodiment)
    parts = registry.load_yaml(embodiment_path)
    return {"task": registry.catalog_path("tasks", task), "embodiment": embodiment_path,
            "arm": registry.catalog_path("arms", str(parts.get("arm")), "arm"),
            "hand": registry.catalog_path("hands", str(parts.get("hand")), "hand")}


def content_hash(files: dict[str, Path]) -> str:
    """sha256 over the roles and bytes of the files, in role order (16 hex digits)."""
    digest = hashlib.sha256()
    for role in sorted(files):
        data = Path(files[role]).read_bytes()
        digest.update(f"{role}:{len(data)}:".encode())
        digest.update(data)
    return digest.hexdigest()[:16]


def setting_content_hash(task: str, embodiment: str) -> str:
    return content_hash(setting_source_files(task, embodiment))
