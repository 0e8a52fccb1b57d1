"""`b2d tables --records FILE... --out DIR`: the paper's Table 2 and per-policy summaries from
per-episode records (result_tables/README.md has the columns a records file must carry)."""

from __future__ import annotations

from pathlib import Path

import click

from evaluation.bootstrap_defaults import N_BOOT, SEED


@click.command("tables")
@click.option("--records", "records", multiple=True, required=True, type=click.Path(path_type=Path),
              help="Records file (parquet or CSV) or a folder of them; repeat, or list several after it.")
@click.argument("more", nargs=-1, metavar="[FILE]...", type=click.Path(path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(path_type=Path),
              help="Output folder (replaced only if it holds an earlier `b2d tables` output).")
@click.option("--resamples", default=N_BOOT, show_default=True, type=click.IntRange(min=100),
              help="Bootstrap resamples for the SR intervals.")
@click.option("--seed", default=SEED, show_default=True, type=int, help="Bootstrap seed.")
@click.option("--profile-hash", default=None, help="Sensor profile hash, when the records do not carry one.")
@click.option("--horizon-rule", default=None, help="How the episode budget was set, when the records do not say.")
@click.option("--seed-rule", default=None, help="How episode seeds were derived (recorded in the metadata).")
def tables(records, more, out_dir, resamples, seed, profile_hash, horizon_rule, seed_rule) -> None:
    """Build summary.json, tables.md, tables.tex, index.html and the PNG figures from records files."""
    from result_tables import RecordsError, build_tables

    given = {"sensor_profile_hash": profile_hash, "horizon_rule": horizon_rule, "episode_seed_rule": seed_rule}
    try:
        summary, _ = build_tables([*records, *more], out_dir, n_boot=resamples, seed=seed, given=given)
    except RecordsError as exc:
        raise click.ClickException(str(exc)) from exc
    except FileExistsError as exc:
        raise click.ClickException(f"{exc}: exists and is not an earlier `b2d tables` output; choose another --out")
    meta = summary["metadata"]
    click.echo(f"{len(summary['rows'])} rows, {meta['N_per_cell']['cells']} cells, "
               f"{meta['N_per_cell']['episodes']} episodes -> {out_dir}")
    for s in summary["policy_summaries"]:
        sr = "n/a" if s["SR"] is None else f"{100 * s['SR']:.1f}%"
        lscr = "n/a" if s["LSCR"] is None else f"{100 * s['LSCR']:.1f}%"
        click.echo(f"  {s['policy']}: SR {sr}, LSCR {lscr} over {s['n_tasks']} task(s)")
