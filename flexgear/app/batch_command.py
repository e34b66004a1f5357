"""``flexgear batch SWEEP.toml -o DIR``: the command-line options (see :mod:`flexgear.app.batch`).

Kept apart from :mod:`flexgear.app.batch` so that building the CLI's parser stays light.
"""
from __future__ import annotations

import sys

from .sweep import DEFAULT_MAX_CASES


def add_batch_command(subparsers):
    """Register ``flexgear batch`` on the CLI's subparsers."""
    b = subparsers.add_parser("batch", help="run a parameter sweep (TOML) on all cores or a Dask cluster; "
                                            "resumable",
                              description="Run every case of a sweep file: one result file per case in "
                              "OUTDIR/cases and a summary table (summary.csv, summary.nc). Every case is validated "
                              "before any runs; rerunning the command continues where it stopped.")
    b.add_argument("sweep", metavar="SWEEP", help="sweep file (TOML): base configuration and axes, see "
                   "docs/guide/batch.md")
    b.add_argument("-o", "--output", metavar="OUTDIR", required=True,
                   help="batch directory (required; created, or continued if it holds a batch)")
    g = b.add_mutually_exclusive_group()
    g.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: one per core; 1 = in this process)")
    g.add_argument("--scheduler", metavar="ADDRESS", help="run on the Dask cluster of this scheduler")
    g.add_argument("--dask-local", type=int, metavar="N", help="start a local Dask cluster of N workers")
    b.add_argument("--retry-failed", action="store_true", help="run the cases that failed before again")
    b.add_argument("--max-cases", type=int, default=DEFAULT_MAX_CASES,
                   help=f"refuse larger sweeps without --yes (default {DEFAULT_MAX_CASES})")
    b.add_argument("--yes", action="store_true", help="run a sweep larger than --max-cases")
    b.add_argument("--dry-run", action="store_true", help="validate and list the cases; run nothing")
    b.set_defaults(func=cmd_batch)
    return b


def cmd_batch(args) -> int:
    """Run the batch; exit status 0 when every case is done, 1 when some failed."""
    max_cases = None if args.yes else args.max_cases
    if args.dry_run:
        return dry_run(args.sweep, max_cases)
    from .batch import run_batch

    try:
        report = run_batch(args.sweep, args.output, workers=args.workers, scheduler=args.scheduler,
                           dask_local=args.dask_local, retry_failed=args.retry_failed, max_cases=max_cases)
    except KeyboardInterrupt:
        print("flexgear batch: interrupted; finished cases are kept, rerun the same command to continue",
              file=sys.stderr)
        return 130
    return 0 if report.failed == 0 and report.pending == 0 else 1


def dry_run(sweep_path, max_cases, out=None, err=None) -> int:
    """``--dry-run``: the sweep's size and axes at once, then every case once, as soon as it is
    built and validated (a sweep of 10^6 cases takes long to validate: its list streams), each
    warning once as it first appears. A case that breaks a rule stops the listing with the
    error, as a run would before starting."""
    from .sweep import open_sweep

    out = sys.stdout if out is None else out
    err = sys.stderr if err is None else err
    plan = open_sweep(sweep_path, max_cases=max_cases)
    print(f"{plan.title}: {plan.n_cases} cases, axes "
          + (" x ".join(f"{a.name} ({len(a)})" for a in plan.axes) or "none"), file=out, flush=True)
    shown = 0
    for c in plan.cases():
        for w in plan.warnings[shown:]:
            print(f"warning: {w}", file=err, flush=True)
        shown = len(plan.warnings)
        print(f"{c.key}  {c.label()}", file=out, flush=True)
    return 0
