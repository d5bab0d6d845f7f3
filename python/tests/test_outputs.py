"""Scenario runs of the CLI: every example scenario runs (short) and its outputs parse
with real readers (meshio for VTU/PVD, pygltflib for GLB); CSV and summary schemas hold
and agree; bad scenarios fail with a message naming the problem; an interrupted run leaves
the frames written so far valid."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python 3.10
    import tomli as tomllib

import meshio
import numpy as np
import pygltflib
import pytest

ROOT = Path(__file__).resolve().parents[2]
CLI = ROOT / "target" / "release" / "myoslice"
SCENARIOS = sorted((ROOT / "assets" / "scenarios").glob("*.toml"))


# For each VTK hexahedron corner, its three edge neighbours in right-handed order.
CORNER_NEIGHBOURS = [(1, 3, 4), (2, 0, 5), (3, 1, 6), (0, 2, 7), (7, 5, 0), (4, 6, 1), (5, 7, 2), (6, 4, 3)]


def folded_hexahedra(path: Path) -> int:
    """Hexahedra of a VTU frame with a corner Jacobian at or below zero: those ParaView's
    mesh quality filter calls invalid, counted the way a user would."""
    m = meshio.read(path)
    hexes = [c for c in m.cells if c.type == "hexahedron"][0].data
    p = np.asarray(m.points, dtype=np.float64)
    worst = np.full(len(hexes), np.inf)
    for c, (a, b, d) in enumerate(CORNER_NEIGHBOURS):
        o = p[hexes[:, c]]
        j = np.einsum("ij,ij->i", p[hexes[:, a]] - o, np.cross(p[hexes[:, b]] - o, p[hexes[:, d]] - o))
        worst = np.minimum(worst, j)
    return int(np.count_nonzero(worst <= 0.0))


def cli() -> Path:
    if not CLI.exists():
        if os.environ.get("MYOSLICE_ALLOW_MISSING_CLI") == "1":
            pytest.skip("myoslice CLI not built")
        pytest.fail(f"{CLI} not found: build it with `cargo build --release -p myoslice-cli`")
    return CLI


def run(scenario: Path, out: Path, duration: float = 0.2) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [str(cli()), "run", str(scenario), "--out", str(out), "--quiet", "--duration", str(duration)],
        capture_output=True,
        text=True,
        timeout=600,
    )


def test_there_are_the_four_example_scenarios() -> None:
    names = {p.stem for p in SCENARIOS}
    assert {"knee_flexion", "knee_extension", "co_contraction", "fast_flexion"} <= names


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda p: p.stem)
def test_each_example_scenario_runs_and_its_outputs_parse(scenario: Path, tmp_path: Path) -> None:
    tissue = tomllib.loads(scenario.read_text()).get("tissue", {}).get("enabled", True)
    r = run(scenario, tmp_path)
    assert r.returncode == 0, r.stderr
    # ParaView series: the PVD lists every VTU, each readable with its cell data.
    pvd = ET.parse(tmp_path / "series.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert len(files) >= 2
    for f in files:
        m = meshio.read(tmp_path / f)
        kinds = {c.type for c in m.cells}
        assert {"hexahedron", "triangle"} <= kinds
        # Without tissue the fat rides rigidly and carries no deformation measures.
        measured = ("area_change", "deformation_degree", "volume_ratio") if tissue else ()
        for key in ("structure_id", "kind", *measured):
            assert key in m.cell_data, key
        hexes = [c for c in m.cells if c.type == "hexahedron"][0].data
        assert hexes.max() < len(m.points)
        assert np.isfinite(m.points).all()
    # Blender: a glTF 2.0 binary with the skin's morph targets and an animation.
    g = pygltflib.GLTF2().load(str(tmp_path / "motion.glb"))
    assert g.asset.version == "2.0"
    assert g.animations and g.animations[0].channels
    skin = [m for m in g.meshes if m.name == "skin"][0]
    assert len(skin.primitives[0].targets) == len(files) - 1
    # Y up: the leg's long axis is the glTF y axis.
    pos = g.accessors[skin.primitives[0].attributes.POSITION]
    extent = np.array(pos.max) - np.array(pos.min)
    assert extent[1] == extent.max()
    # Time series and summary.
    with open(tmp_path / "timeseries.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cols = rows[0].keys()
    for c in ("time_s", "knee_angle_deg", "knee_velocity_deg_s", "knee_torque_nm", "semitendinosus_force_n", "semitendinosus_activation", "semitendinosus_excitation"):
        assert c in cols, c
    t = np.array([float(r["time_s"]) for r in rows])
    assert np.all(np.diff(t) > 0)
    angles = np.array([float(r["knee_angle_deg"]) for r in rows])
    summary = json.loads((tmp_path / "summary.json").read_text())
    for key in ("knee_angle_range_deg", "min_fat_volume_ratio", "max_abs_area_change", "muscle_volume_ratio_range", "inverted_elements", "final_inverted_elements", "wall_time_s", "realtime_factor", "final_knee_angle_deg"):
        assert key in summary, key
    assert summary["knee_angle_range_deg"][0] == pytest.approx(angles.min(), abs=1e-4)
    assert summary["knee_angle_range_deg"][1] == pytest.approx(angles.max(), abs=1e-4)
    assert summary["final_knee_angle_deg"] == pytest.approx(angles[-1], abs=1e-4)
    assert summary["frames"] == len(files)
    assert summary["duration_s"] == pytest.approx(t[-1], abs=2e-3)
    assert summary["rows"] == len(rows)
    assert summary["realtime_factor"] == pytest.approx(summary["duration_s"] / summary["wall_time_s"], rel=1e-6)
    if not tissue:
        return
    # The tissue extremes agree with the frames written (the summary may also have seen
    # tissue updates between frames, so it is at least as extreme).
    def fat_cells(f: str, key: str) -> np.ndarray:
        m = meshio.read(tmp_path / f)
        block = [i for i, c in enumerate(m.cells) if c.type == "hexahedron"][0]
        return np.asarray(m.cell_data[key][block])

    ratios = np.concatenate([fat_cells(f, "volume_ratio") for f in files])
    areas = np.concatenate([fat_cells(f, "area_change") for f in files])
    assert summary["min_fat_volume_ratio"] <= ratios.min() + 1e-6
    assert summary["max_abs_area_change"] >= np.abs(areas).max() - 1e-6
    # No element turns inside out as a whole; the elements with a folded corner are
    # counted as ParaView counts them on the frames (the summary may also have seen
    # updates between frames, so it has at least as many).
    assert ratios.min() > 0.0
    folded = [folded_hexahedra(tmp_path / f) for f in files]
    assert summary["inverted_elements"] >= max(folded)
    assert summary["final_inverted_elements"] == folded[-1]
    # The guard's interventions: counted over the run, vertices only where updates were.
    guard = summary["guard"]
    assert isinstance(guard["updates"], int) and isinstance(guard["vertices"], int)
    assert guard["updates"] <= guard["vertices"]
    assert (guard["updates"] == 0) == (guard["vertices"] == 0)


def test_the_papers_experiment_flexes_the_knee_with_finite_tissue(tmp_path: Path) -> None:
    r = run(ROOT / "assets" / "scenarios" / "knee_flexion.toml", tmp_path, duration=0.3)
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["knee_angle_range_deg"][1] > 20.0, "the knee flexes (positive angles)"
    assert s["knee_angle_range_deg"][0] >= -0.5
    last = meshio.read(tmp_path / f"frame_{s['frames'] - 1:04d}.vtu")
    assert np.isfinite(last.points).all()
    assert s["min_fat_volume_ratio"] > 0.0, "no fat element turned inside out"
    assert s["inverted_elements"] >= folded_hexahedra(tmp_path / f"frame_{s['frames'] - 1:04d}.vtu")
    assert 0.99 < s["muscle_volume_ratio_range"][0] <= s["muscle_volume_ratio_range"][1] < 1.01


def test_an_audited_run_counts_folds_as_paraview_does_on_every_frame(tmp_path: Path) -> None:
    # Deep into the fast flexion, where fat folds (about 127 degrees at 0.3 s).
    r = subprocess.run(
        [str(cli()), "run", str(ROOT / "assets" / "scenarios" / "fast_flexion.toml"), "--out", str(tmp_path), "--quiet", "--duration", "0.3", "--audit"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert r.returncode == 0, r.stderr
    with open(tmp_path / "audit.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    updates = [int(row["tissue_update"]) for row in rows]
    assert updates == list(range(len(rows))), "every tissue update audited, in order"
    summary = json.loads((tmp_path / "summary.json").read_text())
    audit = summary["audit"]
    assert audit["updates"] == len(rows)
    folded = [int(row["folded_fat"]) for row in rows]
    assert audit["worst"]["folded_fat"] == max(folded) > 0
    assert audit["last"]["folded_fat"] == folded[-1]
    assert audit["worst"]["muscles_in_muscles"]["vertices_over_1mm"] == max(int(row["muscle_vertices_in_muscle"]) for row in rows)
    # Each frame shows the tissue of the last update audited by its time: the audit's
    # count is the one ParaView's quality filter gives on that frame.
    pvd = ET.parse(tmp_path / "series.pvd").getroot()
    for d in pvd.iter("DataSet"):
        t = float(d.get("timestep"))
        row = [row for row in rows if float(row["time_s"]) <= t + 1e-9][-1]
        assert int(row["folded_fat"]) == folded_hexahedra(tmp_path / d.get("file")), (t, row)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("[simulation]\nduration_s = 1\nbogus = 1\n", "bogus"),
        ("[simulation]\nduration_s = \"long\"\n", "duration_s"),
        ("[simulation]\nduration_s = -1\n", "duration_s"),
        ("[simulation]\nduration_s = 1\n[excitation]\nsemitendinosis = [[0.0, 0.5]]\n", "semitendinosus"),
        ("[model]\nsource = \"nifti\"\nvolume = \"missing.nii.gz\"\nlabels = \"missing.json\"\n[simulation]\nduration_s = 1\n", "missing.nii.gz"),
    ],
    ids=["unknown-key", "wrong-type", "negative-duration", "unknown-muscle", "missing-model-file"],
)
def test_bad_scenarios_fail_with_a_message_naming_the_problem(text: str, needle: str, tmp_path: Path) -> None:
    sc = tmp_path / "bad.toml"
    sc.write_text(text)
    r = subprocess.run([str(cli()), "run", str(sc), "--out", str(tmp_path / "out"), "--quiet"], capture_output=True, text=True, timeout=300)
    assert r.returncode != 0
    assert needle in r.stderr, r.stderr
    assert "panicked" not in r.stderr


def test_an_interrupted_run_leaves_valid_frames(tmp_path: Path) -> None:
    # Ctrl-C as in a terminal: the run gets SIGINT's default action even when this test
    # runs under a shell that ignores SIGINT (a background job of a script does, and
    # its children inherit that; the run then finished and the test proved nothing).
    p = subprocess.Popen(
        [str(cli()), "run", str(ROOT / "assets" / "scenarios" / "knee_flexion.toml"), "--out", str(tmp_path), "--quiet"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    # Wait for a few frames, then interrupt.
    deadline = time.time() + 300
    while time.time() < deadline and len(list(tmp_path.glob("frame_*.vtu"))) < 3:
        time.sleep(0.2)
    p.send_signal(signal.SIGINT)
    code = p.wait(timeout=60)
    assert code != 0, "the run finished before it was interrupted: the test proves nothing"
    assert not (tmp_path / "summary.json").exists(), "an interrupted run writes no summary"
    pvd = ET.parse(tmp_path / "series.pvd").getroot()
    files = [d.get("file") for d in pvd.iter("DataSet")]
    assert 3 <= len(files) < 31, f"{len(files)} frames listed of the scenario's 31"
    for f in files:
        assert np.isfinite(meshio.read(tmp_path / f).points).all()
    # A temporary *.partial file may remain from the frame being written; it is never listed.
    rows = (tmp_path / "timeseries.csv").read_text().splitlines()
    assert all(len(r.split(",")) == len(rows[0].split(",")) for r in rows)
