"""A Dagster run leaves this process's SIGTERM as it found it, when the chain runs it.

Dagster maps SIGTERM to SIGINT's handler when a run's interrupt capture ends; in a background job of a
non-interactive shell SIGINT is ignored, so without `signal_handlers_kept` the process (and every child
it starts afterwards) would ignore SIGTERM for good."""

import signal

import dagster as dg

from b2d_pipeline.chain import signal_handlers_kept


@dg.asset
def a_number() -> int:
    return 1


def _with_sigint_ignored(run) -> object:
    saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)       # as in `b2d materialize &` from a script
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        run()
        return signal.getsignal(signal.SIGTERM)
    finally:
        for sig, handler in saved.items():
            signal.signal(sig, handler)


def test_a_bare_dagster_run_leaves_sigterm_ignored():
    """The fault itself, so that the test below means something on this Dagster version."""
    assert _with_sigint_ignored(lambda: dg.materialize([a_number])) == signal.SIG_IGN


def test_a_run_inside_signal_handlers_kept_leaves_sigterm_as_it_was():
    def run():
        with signal_handlers_kept():
            assert dg.materialize([a_number]).success

    assert _with_sigint_ignored(run) == signal.SIG_DFL
