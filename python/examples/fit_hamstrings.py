"""Recovering the hamstrings' strength from a knee trajectory with Ray Tune.

Makes a synthetic "measured" trajectory by running ``hamstring_fit.toml`` with the
hamstrings' maximum force at ``--truth`` times the catalogue's, then fits that factor
back (:func:`myoslice.fit.fit`) from the range 0.5 to 2 and prints how close it came.

    python examples/fit_hamstrings.py [--truth 1.3] [--workers 2] [--out fit-out]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import myoslice
from myoslice.fit import fit

SCENARIO = Path(__file__).resolve().parents[2] / "assets" / "scenarios" / "hamstring_fit.toml"
PARAMETER = "muscle.hamstrings.max_force_scale"


def synthetic_target(truth: float, folder: Path) -> Path:
    """Runs the scenario with the true factor; its time series is the target."""
    text = SCENARIO.read_text() + f"\n[muscle.hamstrings]\nmax_force_scale = {truth!r}\n"
    run = folder / "truth"
    myoslice.run_scenario(SCENARIO, run, text=text)
    return run / "timeseries.csv"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--truth", type=float, default=1.3, help="true max force factor")
    ap.add_argument("--workers", type=int, default=None, help="local Ray CPUs (default all)")
    ap.add_argument("--rounds", type=int, default=4, help="grid refinements")
    ap.add_argument("--out", type=Path, default=None, help="keep fit.json and the trials here")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        target = synthetic_target(args.truth, Path(tmp))
        result = fit(
            SCENARIO,
            target,
            {PARAMETER: (0.5, 2.0)},
            rounds=args.rounds,
            out=args.out,
            workers=args.workers,
        )
    found = result.params[PARAMETER]
    off = abs(found / args.truth - 1.0)
    print(
        f"{PARAMETER}: true {args.truth}, fitted {found:.4f} ({100 * off:.2f} % off), "
        f"rms error {result.rms_error_deg:.3f} deg over {result.trials} runs"
    )
    return 0 if off <= 0.05 else 1


if __name__ == "__main__":
    sys.exit(main())
