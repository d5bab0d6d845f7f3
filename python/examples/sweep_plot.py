"""A sweep and its plot: the largest area change of a fat element's outer face against the
knee's peak flexion,
over body mass and hamstring strength (16 runs of the paper's knee flexion, cut to 1 s).

    python examples/sweep_plot.py [--out sweep-out] [--png area_change.png] [--workers 2]

Reads the Parquet table with pandas, as a user would.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from myoslice.sweep import sweep  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "assets" / "scenarios" / "knee_flexion.toml"

SWEEP = f"""
scenario = "{SCENARIO}"
method = "latin_hypercube"
runs = 16
seed = 4
[parameters]
"simulation.duration_s" = [1.0]
"body.mass_kg" = {{ min = 50.0, max = 90.0 }}
"muscle.hamstrings.max_force_scale" = {{ min = 0.6, max = 1.4 }}
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", type=Path, default=None, help="sweep folder (default: temporary)")
    ap.add_argument("--png", type=Path, default=Path("sweep_area_change.png"))
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args()
    import pandas as pd  # type: ignore[import-untyped]

    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or Path(tmp) / "out"
        path = Path(tmp) / "sweep.toml"
        path.write_text(SWEEP)
        df = pd.read_parquet(sweep(path, out, workers=args.workers))
    ok = df[df.error.isna()]
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=110)
    points = ax.scatter(
        ok.peak_knee_angle_deg,
        100.0 * ok.peak_area_change,
        c=ok["muscle.hamstrings.max_force_scale"],
        s=10.0 + 0.8 * (ok["body.mass_kg"] - 40.0),
        cmap="viridis",
    )
    fig.colorbar(points, label="hamstrings' max force (× catalogue)")
    ax.set_xlabel("peak knee flexion (deg)")
    ax.set_ylabel("largest area change of a fat element (%)")
    ax.set_title(f"{len(ok)} runs, knee flexion 1 s (dot size: body mass 50–90 kg)")
    fig.tight_layout()
    fig.savefig(args.png)
    print(f"{len(ok)} runs ({len(df) - len(ok)} failed) -> {args.png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
