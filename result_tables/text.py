"""Markdown and LaTeX (booktabs) renderings of the summary: Table 2's layout (task, embodiment, then
per policy None / Equi. / Inv. / Full counts, SR, LSCR; the task-mean row), the per-policy summary
and the task-level leads. The best SR and LSCR of each task are in bold, as in the paper."""

from __future__ import annotations

from result_tables.provenance import one_line

NA_MD, NA_TEX = "—", "--"


def pct(v, digits: int = 1) -> str | None:
    return None if v is None else f"{100 * v:.{digits}f}%"


def ci(pair) -> str:
    lo, hi = pair
    return "" if lo is None else f" [{100 * lo:.1f}, {100 * hi:.1f}]"


def uniform_n(summary: dict) -> bool:
    n = summary["metadata"]["N_per_cell"]
    return n["min"] == n["max"]


def grid(summary: dict) -> list[dict]:
    """Table 2 lines: per task, per policy the six entries as (text, bold) pairs, None where absent."""
    rows = {(r["task"], r["embodiment"], r["policy"]): r for r in summary["rows"]}
    same_n = uniform_n(summary)
    lines = []
    for task, emb in summary["tasks"]:
        mine = [rows.get((task, emb, p)) for p in summary["policies"]]
        best = {m: max((r[m] for r in mine if r and r[m] is not None), default=None) for m in ("SR", "LSCR")}
        groups = []
        for r in mine:
            if r is None:
                groups.append([None] * 6)
                continue
            entries = []
            for ch in summary["channels"]:
                c = r["channels"][ch["name"]]
                entries.append(None if c is None else (f"{c['n_success']}" if same_n else f"{c['n_success']}/{c['N']}",
                                                       False))
            for m in ("SR", "LSCR"):
                v = r[m]
                entries.append(None if v is None else (pct(v), best[m] is not None and v >= best[m] - 1e-12))
            groups.append(entries)
        lines.append({"task": task, "embodiment": emb, "groups": groups})
    return lines


def macro_entries(s: dict, channels: list[dict]) -> list[str | None]:
    return [pct(s["by_channel"][ch["name"]]["SR"]) for ch in channels] + [pct(s["SR"]), pct(s["LSCR"])]


# --------------------------------------------------------------------------------------------- Markdown
def _md_cell(entry) -> str:
    if entry is None:
        return NA_MD
    text, bold = entry
    return f"**{text}**" if bold else text


def markdown(summary: dict) -> str:
    chans, policies = summary["channels"], summary["policies"]
    labels = [c["label"] for c in chans] + ["SR", "LSCR"]
    out = ["# Result tables", "", *[f"- {line}" for line in one_line(summary["metadata"])], ""]
    out += ["## Stable-success counts across generalization channels", "",
            ("Each entry is the number of reach-and-stop successes among N rollouts"
             if uniform_n(summary) else "Each entry is successes/N")
            + "; SR and LSCR are the four-channel means per task and policy; the last row is the task-macro SR "
              "per channel and the all-task mean LSCR.", ""]
    head = ["Task", "Embodiment"] + [f"{p} {lab}" for p in policies for lab in labels]
    out += ["| " + " | ".join(head) + " |", "|" + "|".join(["---"] * 2 + ["---:"] * (len(head) - 2)) + "|"]
    for line in grid(summary):
        cells = [_md_cell(e) for g in line["groups"] for e in g]
        out.append("| " + " | ".join([_md_escape(line["task"]), _md_escape(line["embodiment"]), *cells]) + " |")
    macro = [e or NA_MD for s in summary["policy_summaries"] for e in macro_entries(s, chans)]
    out.append("| **Task mean (%)** |  | " + " | ".join(macro) + " |")
    out += ["", "## Per policy", "",
            "Task-mean SR per channel with 95% bootstrap intervals, the four-channel SR, the all-task mean LSCR, "
            "the Full/None SR ratio and the number of tasks where Full is below / equal to / above None and "
            "where Inv. is higher than / equal to / lower than Equi.", ""]
    head = ["Policy", "Tasks", *[c["label"] for c in chans], "SR", "LSCR", "Full/None", "Full <,=,> None",
            "Inv. >,=,< Equi."]
    out += ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for s in summary["policy_summaries"]:
        by = s["by_channel"]
        chan = [(pct(by[c["name"]]["SR"]) or NA_MD) + ci(by[c["name"]]["SR_ci"]) for c in chans]
        fn, ie = s["full_vs_none"], s["inv_vs_equi"]
        out.append("| " + " | ".join([
            _md_escape(s["policy"]), str(s["n_tasks"]), *chan, (pct(s["SR"]) or NA_MD) + ci(s["SR_ci"]),
            pct(s["LSCR"]) or NA_MD, pct(s["full_none_ratio"]) or NA_MD,
            f"{fn['below']}/{fn['equal']}/{fn['above']}", f"{ie['higher']}/{ie['equal']}/{ie['lower']}"]) + " |")
    out += ["", "## Task-level leaders per channel", "",
            "Tasks on which a policy has the strictly highest SR; ties at the top are counted apart.", ""]
    head = ["Channel", *[_md_escape(p) for p in policies], "Ties", "Tasks"]
    out += ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    for c in chans:
        lead = summary["leads"][c["name"]]
        out.append("| " + " | ".join([c["label"], *[str(lead["strict_leads"][p]) for p in policies],
                                      str(lead["ties"]), str(lead["n_tasks"])]) + " |")
    return "\n".join(out) + "\n"


def _md_escape(text: str) -> str:
    return str(text).replace("|", "\\|")


# ------------------------------------------------------------------------------------------------ LaTeX
_TEX = {"\\": r"\textbackslash{}", "&": r"\&", "%": r"\%", "$": r"\$", "#": r"\#", "_": r"\_", "{": r"\{",
        "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}


def tex_escape(text) -> str:
    return "".join(_TEX.get(ch, ch) for ch in str(text))


def _tex_cell(entry) -> str:
    if entry is None:
        return NA_TEX
    text, bold = entry
    text = tex_escape(text)
    return rf"\textbf{{{text}}}" if bold else text


def latex(summary: dict) -> str:
    chans, policies = summary["channels"], summary["policies"]
    width = 2 + 6 * len(policies)
    meta = [f"% {line}" for line in one_line(summary["metadata"])]
    out = ["% Generated by `b2d tables`. Requires \\usepackage{booktabs,multirow,graphicx}.", *meta,
           r"\begin{table*}[t]", r"  \centering",
           r"  \caption{\textbf{Stable-success counts across generalization channels.} Each entry is the number of "
           + ("reach-and-stop successes among " + str(summary["metadata"]["N_per_cell"]["min"]) + " rollouts"
              if uniform_n(summary) else "reach-and-stop successes / rollouts")
           + r". \textbf{SR} and \textbf{LSCR} are the four-channel mean stable success rate and latched stage "
             r"completion rate. The bottom row reports the equal-weight task-macro SR (\%) and the all-task mean LSCR.}",
           r"  \label{tab:b2d_generalization_results}",
           r"  \resizebox{\textwidth}{!}{%",
           r"  \begin{tabular}{@{}ll" + "".join("*{6}{c}" for _ in policies) + "@{}}",
           r"    \toprule",
           r"    \multicolumn{1}{c}{\multirow{2}{*}{\textbf{Task}}} & \multicolumn{1}{c}{\multirow{2}{*}{\textbf{Embodiment}}}"
           + "".join(rf" & \multicolumn{{6}}{{c}}{{\textbf{{{tex_escape(p)}}}}}" for p in policies) + r" \\",
           "    " + " ".join(rf"\cmidrule(lr){{{3 + 6 * i}-{8 + 6 * i}}}" for i in range(len(policies))),
           "    &" + "".join(" & " + " & ".join(rf"\textbf{{{lab}}}" for lab in [c["label"] for c in chans] + ["SR", "LSCR"])
                            for _ in policies) + r" \\",
           r"    \midrule"]
    lines = grid(summary)
    for i, line in enumerate(lines):
        first = i == 0 or lines[i - 1]["embodiment"] != line["embodiment"]
        span = 1
        while i + span < len(lines) and lines[i + span]["embodiment"] == line["embodiment"]:
            span += 1
        if first and i:
            out.append(rf"    \cmidrule(lr){{1-{width}}}")
        emb = ""
        if first:
            emb = (rf"\multirow[c]{{{span}}}{{*}}{{{tex_escape(line['embodiment'])}}}" if span > 1
                   else tex_escape(line["embodiment"]))
        cells = [_tex_cell(e) for g in line["groups"] for e in g]
        out.append("    " + " & ".join([tex_escape(line["task"]), emb, *cells]) + r" \\")
    macro = [tex_escape(e) if e else NA_TEX for s in summary["policy_summaries"] for e in macro_entries(s, chans)]
    out += [r"    \midrule", r"    \multicolumn{2}{c}{\textbf{Task mean (\%)}} & " + " & ".join(macro) + r" \\",
            r"    \bottomrule", r"  \end{tabular}%", r"  }", r"\end{table*}", ""]
    out += _latex_policies(summary)
    return "\n".join(out) + "\n"


def _latex_policies(summary: dict) -> list[str]:
    chans = summary["channels"]
    out = [r"\begin{table}[t]", r"  \centering",
           r"  \caption{Per policy: task-mean SR per channel with 95\% bootstrap intervals, four-channel SR, all-task "
           r"mean LSCR, Full/None SR ratio, tasks with Full below/equal/above None and with Inv.\ "
           r"higher/equal/lower than Equi.}",
           r"  \label{tab:b2d_policy_summary}", r"  \resizebox{\linewidth}{!}{%",
           r"  \begin{tabular}{@{}l" + "c" * (len(chans) + 5) + "@{}}", r"    \toprule",
           "    " + " & ".join([r"\textbf{Policy}", *[rf"\textbf{{{c['label']}}}" for c in chans], r"\textbf{SR}",
                                r"\textbf{LSCR}", r"\textbf{Full/None}", r"\textbf{Full $<$/$=$/$>$ None}",
                                r"\textbf{Inv.\ $>$/$=$/$<$ Equi.}"]) + r" \\", r"    \midrule"]
    for s in summary["policy_summaries"]:
        by = s["by_channel"]
        chan = [tex_escape((pct(by[c["name"]]["SR"]) or NA_TEX) + ci(by[c["name"]]["SR_ci"])) for c in chans]
        fn, ie = s["full_vs_none"], s["inv_vs_equi"]
        out.append("    " + " & ".join([
            tex_escape(s["policy"]), *chan, tex_escape((pct(s["SR"]) or NA_TEX) + ci(s["SR_ci"])),
            tex_escape(pct(s["LSCR"]) or NA_TEX), tex_escape(pct(s["full_none_ratio"]) or NA_TEX),
            f"{fn['below']}/{fn['equal']}/{fn['above']}", f"{ie['higher']}/{ie['equal']}/{ie['lower']}"]) + r" \\")
    out += [r"    \bottomrule", r"  \end{tabular}%", r"  }", r"\end{table}"]
    return out
