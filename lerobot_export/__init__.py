"""HDF5 episodes as a LeRobot dataset (v2.1 or v3.0), with GR00T's meta/modality.json: what pi0.5,
GR00T N1.5 and lerobot's own policies train on. `export_lerobot` is the one entry point."""

from lerobot_export.export import ExportResult, NothingExported, export_lerobot
from lerobot_export.formats import FORMATS
from lerobot_export.video import VideoSettings

__all__ = ["FORMATS", "ExportResult", "NothingExported", "VideoSettings", "export_lerobot"]
