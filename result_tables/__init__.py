"""Result tables like the paper's (Table 2 and its per-policy summaries) from per-episode records: the
records contract (schema.py, README.md), loading with named errors, aggregation, seeded bootstrap and
the writers (summary.json, Markdown, LaTeX, HTML, PNG)."""

from result_tables.build import OUTPUTS, build_tables, summarize, write_outputs
from result_tables.schema import RecordsError

__all__ = ["OUTPUTS", "RecordsError", "build_tables", "summarize", "write_outputs"]
