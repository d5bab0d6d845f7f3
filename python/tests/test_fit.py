"""Fitting muscle parameters to a knee trajectory (``myoslice.fit``, Ray Tune)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

pytest.importorskip("ray.tune", reason="fits need ray[tune] (see requirements-test.txt)")

import myoslice  # noqa: E402
from myoslice.errors import InvalidInputError  # noqa: E402
from myoslice.fit import fit, fit_file  # noqa: E402

SCENARIO = Path(__file__).resolve().parents[2] / "assets" / "scenarios" / "hamstring_fit.toml"
PARAMETER = "muscle.hamstrings.max_force_scale"


def synthetic(folder: Path, truth: float) -> Path:
    text = SCENARIO.read_text() + f"\n[muscle.hamstrings]\nmax_force_scale = {truth!r}\n"
    myoslice.run_scenario(SCENARIO, folder / "truth", text=text)
    return folder / "truth" / "timeseries.csv"


def test_a_fit_recovers_the_hamstrings_strength_from_its_own_trajectory(tmp_path: Path) -> None:
    truth = 1.3
    target = synthetic(tmp_path, truth)
    fit_toml = tmp_path / "fit.toml"
    fit_toml.write_text(
        f'scenario = "{SCENARIO}"\ntarget = "{target}"\nrounds = 4\npoints = 5\n'
        f'[parameters]\n"{PARAMETER}" = {{ min = 0.5, max = 2.0 }}\n'
    )
    result = fit_file(fit_toml, tmp_path / "out", workers=2)
    found = result.params[PARAMETER]
    assert abs(found / truth - 1.0) <= 0.05, result
    # 5 points a round, the ones met before not run again.
    assert 5 < result.trials < 20, result.trials
    # Each round is at least as good as the one before.
    errors = [r["rms_error_deg"] for r in result.rounds]
    assert errors == sorted(errors, reverse=True), errors
    saved = json.loads((tmp_path / "out" / "fit.json").read_text())
    assert saved["params"][PARAMETER] == found


def test_bad_fits_are_refused_before_any_run(tmp_path: Path) -> None:
    target = tmp_path / "t.csv"
    target.write_text("time_s,knee_angle_deg\n0.0,0.0\n0.1,5.0\n")
    with pytest.raises(InvalidInputError, match="points = 3"):
        fit(SCENARIO, target, {PARAMETER: (0.5, 2.0)}, points=3)
    with pytest.raises(InvalidInputError, match="min < max"):
        fit(SCENARIO, target, {PARAMETER: (2.0, 1.0)})
    with pytest.raises(InvalidInputError, match="unknown field"):
        fit(SCENARIO, target, {"muscle.hamstrings.strength": (0.5, 2.0)})
    long = tmp_path / "long.csv"
    long.write_text("time_s,knee_angle_deg\n0.0,0.0\n3.0,5.0\n")
    with pytest.raises(InvalidInputError, match="lasts 3.0 s"):
        fit(SCENARIO, long, {PARAMETER: (0.5, 2.0)})
    bad = tmp_path / "bad.csv"
    bad.write_text("t,angle\n0,0\n")
    with pytest.raises(InvalidInputError, match="time_s and knee_angle_deg"):
        fit(SCENARIO, bad, {PARAMETER: (0.5, 2.0)})
