"""One self-contained HTML page: metadata, Table 2, the per-policy summary, the leaders and the three
figures embedded as base64 PNG (no external file, script or font)."""

from __future__ import annotations

import base64
from html import escape

from result_tables.provenance import one_line
from result_tables.text import NA_MD, ci, grid, macro_entries, pct

STYLE = """body{font-family:sans-serif;margin:1.5em;color:#222}table{border-collapse:collapse;font-size:12px;
margin-bottom:1.5em}th,td{border-top:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#f3f3f3}
td.l,th.l{text-align:left}tr.macro td{border-top:2px solid #444;font-weight:bold}.meta{font-size:12px;color:#444}
img{max-width:100%;margin:0.5em 0}"""


def _cell(entry) -> str:
    if entry is None:
        return f"<td>{NA_MD}</td>"
    text, bold = entry
    return f"<td><b>{escape(text)}</b></td>" if bold else f"<td>{escape(text)}</td>"


def page(summary: dict, figures: dict[str, bytes]) -> str:
    chans, policies = summary["channels"], summary["policies"]
    labels = [c["label"] for c in chans] + ["SR", "LSCR"]
    h = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8"><title>b2d result tables</title>',
         f"<style>{STYLE}</style></head><body>", "<h1>Result tables</h1>", '<ul class="meta">',
         *[f"<li>{escape(line)}</li>" for line in one_line(summary["metadata"])], "</ul>",
         "<h2>Stable-success counts across generalization channels</h2>", "<table><thead><tr>",
         '<th class="l" rowspan="2">Task</th><th class="l" rowspan="2">Embodiment</th>',
         *[f'<th colspan="6">{escape(p)}</th>' for p in policies], "</tr><tr>",
         *[f"<th>{escape(lab)}</th>" for _ in policies for lab in labels], "</tr></thead><tbody>"]
    for line in grid(summary):
        h.append(f'<tr><td class="l">{escape(str(line["task"]))}</td><td class="l">{escape(str(line["embodiment"]))}</td>'
                 + "".join(_cell(e) for g in line["groups"] for e in g) + "</tr>")
    macro = [e or NA_MD for s in summary["policy_summaries"] for e in macro_entries(s, chans)]
    h.append('<tr class="macro"><td class="l" colspan="2">Task mean (%)</td>'
             + "".join(f"<td>{escape(e)}</td>" for e in macro) + "</tr></tbody></table>")
    h += ["<h2>Per policy</h2>", "<table><thead><tr>",
          *[f"<th>{escape(x)}</th>" for x in ["Policy", "Tasks", *[c["label"] for c in chans], "SR", "LSCR",
                                               "Full/None", "Full <,=,> None", "Inv. >,=,< Equi."]],
          "</tr></thead><tbody>"]
    for s in summary["policy_summaries"]:
        by, fn, ie = s["by_channel"], s["full_vs_none"], s["inv_vs_equi"]
        vals = [s["policy"], str(s["n_tasks"]),
                *[(pct(by[c["name"]]["SR"]) or NA_MD) + ci(by[c["name"]]["SR_ci"]) for c in chans],
                (pct(s["SR"]) or NA_MD) + ci(s["SR_ci"]), pct(s["LSCR"]) or NA_MD, pct(s["full_none_ratio"]) or NA_MD,
                f"{fn['below']}/{fn['equal']}/{fn['above']}", f"{ie['higher']}/{ie['equal']}/{ie['lower']}"]
        h.append('<tr><td class="l">' + "</td><td>".join(escape(v) for v in vals) + "</td></tr>")
    h += ["</tbody></table>", "<h2>Task-level leaders per channel</h2>", "<table><thead><tr>",
          *[f"<th>{escape(x)}</th>" for x in ["Channel", *policies, "Ties", "Tasks"]], "</tr></thead><tbody>"]
    for c in chans:
        lead = summary["leads"][c["name"]]
        vals = [c["label"], *[str(lead["strict_leads"][p]) for p in policies], str(lead["ties"]), str(lead["n_tasks"])]
        h.append('<tr><td class="l">' + "</td><td>".join(escape(v) for v in vals) + "</td></tr>")
    h += ["</tbody></table>", "<h2>Figures</h2>"]
    for name, png in figures.items():
        h.append(f'<figure><img alt="{escape(name)}" src="data:image/png;base64,{base64.b64encode(png).decode()}">'
                 f"<figcaption>{escape(name)}</figcaption></figure>")
    h.append("</body></html>")
    return "\n".join(h) + "\n"
