"""Command line of the Python package: ``python -m myoslice sweep|fit ...`` (the ``myoslice``
binary's ``sweep`` runs this)."""

from __future__ import annotations

import argparse
import sys

from .errors import MyoSliceError

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="myoslice", description=__doc__)
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("sweep", help="run a sweep file's runs into a folder (Ray or serial)")
    s.add_argument("sweep_file", help="sweep file (TOML)")
    s.add_argument("--out", required=True, help="output folder (results.parquet, runs/)")
    s.add_argument("--address", help="Ray cluster to join (default: a local Ray)")
    s.add_argument("--workers", type=int, help="CPUs of the local Ray (default: all)")
    s.add_argument("--serial", action="store_true", help="no Ray: one run after another")
    s.add_argument("--retry-failed", action="store_true", help="run failed runs again")
    s.add_argument("--limit", type=int, help="run at most this many new runs, then stop")
    s.add_argument("--quiet", action="store_true", help="no progress bar")
    f = sub.add_parser("fit", help="fit muscle parameters to a knee trajectory (Ray Tune)")
    f.add_argument("fit_file", help="fit file (TOML)")
    f.add_argument("--out", required=True, help="output folder (fit.json, trials)")
    f.add_argument("--address", help="Ray cluster to join (default: a local Ray)")
    f.add_argument("--workers", type=int, help="CPUs of the local Ray (default: all)")
    return p


def main(argv: list[str] | None = None) -> int:
    """Runs the command line; returns the exit code."""
    args = _parser().parse_args(argv)
    try:
        if args.command == "sweep":
            from .sweep import read_results, sweep

            path = sweep(
                args.sweep_file,
                args.out,
                address=args.address,
                workers=args.workers,
                serial=args.serial,
                retry_failed=args.retry_failed,
                limit=args.limit,
                progress=False if args.quiet else None,
            )
            table = read_results(args.out)
            errors = [e for e in table.column("error").to_pylist() if e is not None] if (
                "error" in table.column_names
            ) else []
            print(f"{table.num_rows} runs ({len(errors)} failed) -> {path}")
        else:
            from .fit import fit_file

            result = fit_file(args.fit_file, args.out, address=args.address,
                              workers=args.workers)
            shown = ", ".join(f"{k} = {v:.4g}" for k, v in result.params.items())
            print(f"best: {shown} (rms error {result.rms_error_deg:.3f} deg) -> {args.out}")
    except (MyoSliceError, ImportError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    return 0
