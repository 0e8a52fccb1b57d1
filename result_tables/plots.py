"""The three figures as PNG bytes (matplotlib's Agg canvas, no pyplot state): task-mean SR per channel
per policy with bootstrap intervals, the RR heatmap per task (SR_p / SR_None of each shifted channel),
and four-channel SR against LSCR per task and policy. Same summary, same bytes."""

from __future__ import annotations

import io
import json

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

def _png(fig: Figure, meta: dict) -> bytes:
    """PNG bytes with the full metadata as a text chunk; no software version or time, so the bytes
    depend on the numbers only."""
    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110,
                metadata={"Software": None, "Description": json.dumps(meta, sort_keys=True)})
    return buf.getvalue()


def _footer(fig: Figure, meta: dict) -> None:
    """The reproducibility metadata in two short lines under the plot."""
    fig.get_layout_engine().set(h_pad=0.3)
    seeds, n = meta["seeds"], meta["N_per_cell"]
    rng = seeds["episode_seed_range"]
    join = lambda v: ", ".join(v) if v else "n/a"  # noqa: E731
    fig.text(0.01, 0.022, f"{meta['code_version']}  |  sensor profile {join(meta['sensor_profile_hash'])}  |  "
             f"N/cell {n['min']}" + (f"..{n['max']}" if n["max"] != n["min"] else ""), fontsize=5.5, color="0.4")
    fig.text(0.01, 0.004, f"horizon: {join(meta['horizon_rule'])}  |  episode seeds "
             + (f"{rng[0]}..{rng[1]}" if rng else "n/a") + f"  |  bootstrap seed {seeds['bootstrap']['seed']}, "
             f"{seeds['bootstrap']['resamples']} resamples", fontsize=5.5, color="0.4")


def sr_per_channel(summary: dict) -> bytes:
    chans, stats = summary["channels"], summary["policy_summaries"]
    fig = Figure(figsize=(7, 3.8), layout="constrained")
    ax = fig.add_subplot()
    width = 0.8 / max(len(stats), 1)
    x = np.arange(len(chans))
    for i, s in enumerate(stats):
        sr = [s["by_channel"][c["name"]]["SR"] for c in chans]
        ci = [s["by_channel"][c["name"]]["SR_ci"] for c in chans]
        y = np.array([np.nan if v is None else 100 * v for v in sr])
        err = np.array([[0 if v is None or lo is None else 100 * (v - lo) for v, (lo, _) in zip(sr, ci)],
                        [0 if v is None or hi is None else 100 * (hi - v) for v, (_, hi) in zip(sr, ci)]])
        ax.bar(x + (i - (len(stats) - 1) / 2) * width, y, width, yerr=err, capsize=2, label=s["policy"])
    ax.set_xticks(x, [c["label"] for c in chans])
    ax.set_ylabel("task-mean SR (%)")
    ax.set_title("Stable success per channel (95% bootstrap intervals)", fontsize=10)
    ax.legend(fontsize=7, ncols=min(len(stats), 4))
    _footer(fig, summary["metadata"])
    return _png(fig, summary["metadata"])


def rr_heatmap(summary: dict) -> bytes:
    shifted = summary["channels"][1:]
    policies, tasks = summary["policies"], summary["tasks"]
    rows = {(r["task"], r["embodiment"], r["policy"]): r for r in summary["rows"]}
    rr = np.full((len(tasks), len(policies) * len(shifted)), np.nan)
    for i, (task, emb) in enumerate(tasks):
        for j, p in enumerate(policies):
            r = rows.get((task, emb, p))
            base = r and r["channels"]["none"]
            if not base or not base["SR"]:
                continue           # RR undefined: SR_None is 0 or missing
            for k, ch in enumerate(shifted):
                c = r["channels"][ch["name"]]
                if c is not None:
                    rr[i, j * len(shifted) + k] = c["SR"] / base["SR"]
    fig = Figure(figsize=(3.5 + 0.45 * rr.shape[1], 2.2 + 0.26 * len(tasks)), layout="constrained")
    ax = fig.add_subplot()
    vmax = max(1.0, float(np.nanmax(rr)) if np.isfinite(rr).any() else 1.0)
    cmap = _cmap()
    im = ax.imshow(np.ma.masked_invalid(rr), cmap=cmap, vmin=0.0, vmax=vmax, aspect="auto")
    for (i, j), v in np.ndenumerate(rr):
        ax.text(j, i, "n/a" if np.isnan(v) else f"{v:.2f}", ha="center", va="center", fontsize=6,
                color="0.3" if np.isnan(v) else ("white" if v < 0.5 * vmax else "black"))
    ax.set_xticks(range(rr.shape[1]), [f"{p} {c['label']}" for p in policies for c in shifted], fontsize=6,
                  rotation=90)
    ax.set_yticks(range(len(tasks)), [f"{t} ({e})" for t, e in tasks], fontsize=6)
    ax.set_title("RR = SR(channel) / SR(None) per task (n/a: SR None is 0)", fontsize=9)
    fig.colorbar(im, ax=ax, shrink=0.6)
    _footer(fig, summary["metadata"])
    return _png(fig, summary["metadata"])


def _cmap():
    from matplotlib import colormaps
    return colormaps["viridis"].with_extremes(bad="0.88")


def sr_vs_lscr(summary: dict) -> bytes:
    fig = Figure(figsize=(5, 4.6), layout="constrained")
    ax = fig.add_subplot()
    for p in summary["policies"]:
        pts = [(r["SR"], r["LSCR"]) for r in summary["rows"] if r["policy"] == p
               and r["SR"] is not None and r["LSCR"] is not None]
        if pts:
            xs, ys = zip(*pts)
            ax.scatter(100 * np.array(xs), 100 * np.array(ys), s=14, label=p, alpha=0.8)
    ax.plot([0, 100], [0, 100], color="0.6", linewidth=0.8, linestyle="--")
    ax.set_xlim(0, 100)
    ax.set_ylim(0, 100)
    ax.set_xlabel("four-channel SR (%)")
    ax.set_ylabel("four-channel LSCR (%)")
    ax.set_title("SR against LSCR per task and policy", fontsize=10)
    ax.legend(fontsize=7)
    _footer(fig, summary["metadata"])
    return _png(fig, summary["metadata"])


FIGURES = {"sr_per_channel.png": sr_per_channel, "rr_heatmap.png": rr_heatmap, "sr_vs_lscr.png": sr_vs_lscr}
