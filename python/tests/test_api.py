"""The compiled module's API: types, shapes and dtypes of everything in the contract,
stepping, excitations, determinism and checkpoints."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
import pytest

import myoslice
from myoslice import InvalidInputError, Simulation, State

HAMSTRINGS = ("semitendinosus", "semimembranosus", "biceps_femoris_long", "biceps_femoris_short")
PER_MUSCLE_F64 = ("excitations", "activations", "forces", "fibre_lengths", "moment_arms")
PER_FAT_F32 = ("area_change", "deformation_degree", "volume_ratio")
LAYERS = ("bone", "muscle", "skin")


def flex(sim: Simulation, seconds: float = 0.5) -> None:
    """Fully excites the hamstrings for ``seconds``."""
    sim.set_excitations(dict.fromkeys(HAMSTRINGS, 1.0))
    sim.step(0.001, n=round(seconds / 0.001))


def snapshot(sim: Simulation) -> dict[str, object]:
    """Every observable of a simulation, for exact comparisons."""
    out: dict[str, object] = {
        name: getattr(sim, name)
        for name in (
            "time",
            "knee_angle",
            "knee_velocity",
            "knee_torque",
            *PER_MUSCLE_F64,
            *PER_FAT_F32,
            "muscle_volume_ratio",
        )
    }
    for layer in LAYERS:
        out[f"surface_{layer}"] = sim.surface(layer)[0]
    return out


def assert_identical(a: dict[str, object], b: dict[str, object]) -> None:
    assert a.keys() == b.keys()
    for key in a:
        x, y = a[key], b[key]
        if isinstance(x, np.ndarray):
            assert isinstance(y, np.ndarray)
            assert x.dtype == y.dtype, key
            assert np.array_equal(x, y), f"{key} differs"
        else:
            assert type(x) is float and type(y) is float, key
            assert x == y, f"{key}: {x!r} != {y!r}"


# --- module and construction ---------------------------------------------------------


def test_version_is_a_string() -> None:
    assert isinstance(myoslice.__version__, str) and myoslice.__version__


def test_public_names() -> None:
    for name in myoslice.__all__:
        assert hasattr(myoslice, name), name


def test_simulation_has_no_plain_constructor() -> None:
    with pytest.raises(TypeError):
        Simulation()


def test_repr(rigid: Simulation) -> None:
    assert "Simulation" in repr(rigid)
    assert "State" in repr(rigid.state())


# --- names, groups and per-muscle arrays ---------------------------------------------


def test_muscle_names_and_groups(rigid: Simulation) -> None:
    names, groups = rigid.muscle_names, rigid.muscle_groups
    assert isinstance(names, list) and all(isinstance(n, str) for n in names)
    assert len(set(names)) == len(names) > 0
    assert isinstance(groups, list) and len(groups) == len(names)
    assert set(groups) <= {"flexor", "extensor", "other"}
    assert {"flexor", "extensor"} <= set(groups)
    for h in HAMSTRINGS:
        assert h in names
        assert groups[names.index(h)] == "flexor"


@pytest.mark.parametrize("name", PER_MUSCLE_F64)
def test_per_muscle_arrays(rigid: Simulation, name: str) -> None:
    flex(rigid, 0.05)
    a = getattr(rigid, name)
    assert isinstance(a, np.ndarray)
    assert a.dtype == np.float64
    assert a.shape == (len(rigid.muscle_names),)
    assert np.all(np.isfinite(a))


@pytest.mark.parametrize("name", PER_MUSCLE_F64)
def test_arrays_are_fresh_copies(rigid: Simulation, name: str) -> None:
    a = getattr(rigid, name)
    b = getattr(rigid, name)
    assert not np.shares_memory(a, b)
    before = a.copy()
    if a.flags.writeable:
        a[:] = 0.5
        assert np.array_equal(getattr(rigid, name), before)


def test_muscles_respond_to_excitation(rigid: Simulation) -> None:
    names = rigid.muscle_names
    hamstrings = [names.index(h) for h in HAMSTRINGS]
    vasti = [names.index(v) for v in ("vastus_lateralis", "vastus_medialis", "vastus_intermedius")]
    # At rest the hamstrings flex the knee and the vasti extend it, from the start.
    assert np.all(rigid.moment_arms[hamstrings] > 0.0)
    assert np.all(rigid.moment_arms[vasti] < 0.0)
    rigid.step(0.001)
    assert np.all(rigid.moment_arms[hamstrings] > 0.0)
    assert np.all(rigid.moment_arms[vasti] < 0.0)
    rigid.set_excitations(dict.fromkeys(HAMSTRINGS, 1.0))
    peak = np.zeros(len(names))
    for _ in range(20):  # 0.2 s
        rigid.step(0.001, n=10)
        act = rigid.activations
        assert np.all((act >= 0.0) & (act <= 1.0))
        assert np.all(rigid.forces >= 0.0)
        peak = np.maximum(peak, rigid.forces)
    assert np.all(rigid.activations[hamstrings] > 0.5)
    assert np.all(peak[hamstrings] > 0.0), dict(zip(HAMSTRINGS, peak[hamstrings]))
    assert np.all(rigid.fibre_lengths > 0.0)


# --- scalars -------------------------------------------------------------------------


def test_scalar_properties(rigid: Simulation) -> None:
    for name in ("time", "knee_angle", "knee_velocity", "knee_torque"):
        v = getattr(rigid, name)
        assert isinstance(v, float) and math.isfinite(v), name
    lo, hi = rigid.knee_limits
    assert isinstance(rigid.knee_limits, tuple)
    assert isinstance(lo, float) and isinstance(hi, float)
    assert lo < 0.5 < hi
    assert lo <= rigid.knee_angle <= hi
    assert isinstance(rigid.n_fat_elements, int) and rigid.n_fat_elements > 0
    assert rigid.time == 0.0


# --- surfaces ------------------------------------------------------------------------


@pytest.mark.parametrize("layer", LAYERS)
@pytest.mark.parametrize("with_tissue", [False, True], ids=["rigid", "tissue"])
def test_surface(request: pytest.FixtureRequest, layer: str, with_tissue: bool) -> None:
    sim: Simulation = request.getfixturevalue("tissue" if with_tissue else "rigid")
    vertices, triangles = sim.surface(layer)
    assert vertices.dtype == np.float32 and vertices.ndim == 2 and vertices.shape[1] == 3
    assert triangles.dtype == np.uint32 and triangles.ndim == 2 and triangles.shape[1] == 3
    n, m = vertices.shape[0], triangles.shape[0]
    assert n > 0 and m > 0
    assert int(triangles.max()) < n
    assert np.all(np.isfinite(vertices))
    # A leg is tens of centimetres, in metres.
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    assert 0.01 < float(extent.max()) < 3.0
    v2, t2 = sim.surface(layer)
    assert not np.shares_memory(vertices, v2) and not np.shares_memory(triangles, t2)


def test_surface_follows_the_knee(rigid: Simulation) -> None:
    before = rigid.surface("bone")[0]
    flex(rigid, 0.3)
    after = rigid.surface("bone")[0]
    assert before.shape == after.shape
    assert not np.array_equal(before, after)


def test_carried_surface_moves_the_tissue_with_the_bones_between_updates(
    tissue: Simulation, rigid: Simulation
) -> None:
    flex(tissue, 0.2)
    differed = 0
    for _ in range(40):  # more than a tissue period (30 Hz)
        tissue.step(0.001)
        skin, tris = tissue.surface("skin")
        carried, carried_tris = tissue.surface("skin", carried=True)
        assert carried.shape == skin.shape and np.array_equal(carried_tris, tris)
        differed += int(not np.array_equal(carried, skin))
        # Within the knee's turn in a period (the foot's end moves centimetres in a
        # fast flexion), not a different leg.
        assert float(np.abs(carried - skin).max()) < 0.15
    # Between updates the knee moves on and the carried skin with it; at an update the
    # two are the same.
    assert 0 < differed < 40
    assert np.array_equal(tissue.surface("bone", carried=True)[0], tissue.surface("bone")[0])
    muscles = tissue.surface("muscle", carried=True)[0]
    assert muscles.shape == tissue.surface("muscle")[0].shape
    # Without tissue there is nothing to carry.
    flex(rigid, 0.2)
    assert np.array_equal(rigid.surface("skin", carried=True)[0], rigid.surface("skin")[0])


# --- stepping and excitations --------------------------------------------------------


def test_step_advances_time_by_dt_times_n(rigid: Simulation) -> None:
    t0 = rigid.time
    rigid.step()
    assert rigid.time == pytest.approx(t0 + 0.001, rel=0, abs=1e-12)
    rigid.step(0.002, n=5)
    assert rigid.time == pytest.approx(t0 + 0.011, rel=0, abs=1e-12)
    rigid.step(dt=0.0005, n=4)
    assert rigid.time == pytest.approx(t0 + 0.013, rel=0, abs=1e-12)


def test_timers_count_the_rust_side_of_each_step_call(tissue: Simulation) -> None:
    tissue.reset_timers()
    assert tissue.timers["calls"] == 0 and tissue.timers["realtime_factor"] is None
    tissue.step(0.001, n=40)
    t = tissue.timers
    assert set(t) == {
        "calls", "steps", "tissue_updates", "simulated_s", "wall_s", "tissue_wall_s",
        "muscles_wall_s", "realtime_factor", "tissue_phases_s",
    }
    assert (t["calls"], t["steps"]) == (40, 40)
    assert t["simulated_s"] == pytest.approx(0.04, rel=1e-12)
    # 40 ms at the default 30 Hz holds one or two tissue updates.
    assert 1 <= t["tissue_updates"] <= 2
    assert 0.0 < t["tissue_wall_s"] < t["wall_s"]
    assert t["muscles_wall_s"] == pytest.approx(t["wall_s"] - t["tissue_wall_s"])
    assert t["realtime_factor"] == pytest.approx(t["simulated_s"] / t["wall_s"])
    # The phases, in update order, take all of the tissue's time but a call's backup and
    # the finiteness checks.
    phases = t["tissue_phases_s"]
    assert list(phases) == [
        "muscle_shapes", "knee_fold", "first_guess", "shape_matching", "bone_sliding", "guard",
    ]
    seconds = [
        phases["muscle_shapes"], phases["knee_fold"], phases["first_guess"],
        phases["shape_matching"], phases["bone_sliding"], phases["guard"],
    ]
    assert all(s > 0.0 for s in seconds)
    assert 0.9 * t["tissue_wall_s"] < sum(seconds) <= t["tissue_wall_s"] + 1e-9
    # Checkpoints are about the model, timers about the machine.
    tissue.set_state(tissue.state())
    assert tissue.timers == t


def per_muscle_reach(
    r: Mapping[str, Any], distance: str, sim: Simulation
) -> tuple[Any, Any]:
    """The two arrays of a per-muscle reach dict, checked for keys, shapes and dtypes."""
    assert set(r) == {"vertices_over_1mm", distance}
    count, dist = r["vertices_over_1mm"], r[distance]
    n = len(sim.muscle_names)
    assert count.shape == (n,) and count.dtype == np.int64
    assert dist.shape == (n,) and dist.dtype == np.float32
    return count, dist


def test_muscles_in_bone_per_muscle(tissue: Simulation, rigid: Simulation) -> None:
    flex(tissue, 0.3)
    count, deepest = per_muscle_reach(tissue.muscles_in_bone(), "deepest_m", tissue)
    assert (count >= 0).all() and (deepest >= 0.0).all() and np.isfinite(deepest).all()
    # A muscle with a vertex over 1 mm deep counts it, and one that counts none has none.
    assert ((deepest > 1e-3) == (count > 0)).all()
    # The phantom's iliacus lies partly inside the hip bone's surface (up to about 5 mm
    # at rest); nothing goes deeper than a couple of centimetres.
    assert 0.0 < deepest.max() < 0.02
    empty = rigid.muscles_in_bone()
    assert empty["vertices_over_1mm"].shape == (0,) and empty["deepest_m"].shape == (0,)


def test_muscles_outside_skin_per_muscle(tissue: Simulation, rigid: Simulation) -> None:
    # At rest every muscle lies under the skin.
    count, farthest = per_muscle_reach(tissue.muscles_outside_skin(), "farthest_m", tissue)
    assert (count == 0).all() and (farthest < 1e-3).all()
    flex(tissue, 0.3)
    r = tissue.muscles_outside_skin()
    count, farthest = r["vertices_over_1mm"], r["farthest_m"]
    assert (count >= 0).all() and np.isfinite(farthest).all()
    assert ((farthest > 1e-3) == (count > 0)).all()
    empty = rigid.muscles_outside_skin()
    assert empty["vertices_over_1mm"].shape == (0,) and empty["farthest_m"].shape == (0,)


def test_audit_sums_the_per_muscle_measures(tissue: Simulation, rigid: Simulation) -> None:
    flex(tissue, 0.3)
    a = tissue.audit()
    assert a is not None and a["finite"] is True
    out = tissue.muscles_outside_skin()
    assert a["muscles_out_of_skin"]["vertices_over_1mm"] == int(out["vertices_over_1mm"].sum())
    assert a["muscles_out_of_skin"]["farthest_m"] == pytest.approx(float(out["farthest_m"].max()))
    bone = tissue.muscles_in_bone()
    assert a["muscles_in_bone"]["vertices_over_1mm"] == int(bone["vertices_over_1mm"].sum())
    # Folded fat is counted by corner Jacobians, as the tissue metrics count it.
    assert a["folded_fat"] >= 0 and 0.0 < a["min_fat_volume_ratio"] <= 1.0
    assert a["muscles_in_muscles"]["deepest_m"] >= 0.0
    # Skin touching skin, in m²: some once the knee bends, far less than the whole skin.
    assert 0.0 < a["skin_in_contact_m2"] < 0.05
    lo, hi = a["muscle_volume_ratio"]
    assert 0.0 < lo <= hi
    assert rigid.audit() is None


def test_muscle_contact_presses_fewer_muscle_vertices_into_their_neighbours() -> None:
    found = []
    for on in (False, True):
        sim = Simulation.phantom(muscle_contact=on, chain_contact=True)
        flex(sim, 0.3)
        a = sim.audit()
        assert a is not None
        lo, hi = a["muscle_volume_ratio"]
        assert 0.99 < lo <= hi < 1.01, (on, lo, hi)
        found.append(a["muscles_in_muscles"]["vertices_over_1mm"])
    assert found[1] < found[0], found


def test_fat_constraints_leave_fewer_fat_elements_folded() -> None:
    found = []
    for on in (False, True):
        sim = Simulation.phantom(fat_constraints=on)
        flex(sim, 0.3)
        a = sim.audit()
        assert a is not None
        found.append(a["folded_fat"])
    assert 4 * found[1] < found[0], found


def test_bones_outside_skin_per_bone(tissue: Simulation, rigid: Simulation) -> None:
    r = tissue.bones_outside_skin()
    assert set(r) == {"vertices_over_1mm", "farthest_m"}
    count, farthest = r["vertices_over_1mm"], r["farthest_m"]
    n = len(tissue.bone_names)
    assert n > 0 and "patella" in tissue.bone_names
    assert count.shape == (n,) and count.dtype == np.int64
    assert farthest.shape == (n,) and farthest.dtype == np.float32
    assert ((farthest > 1e-3) == (count > 0)).all()
    # The patella lies under the skin at rest, and stays within 2.5 mm of it bent past 110°
    # (about 119° after 0.3 s; from about 70° it came out, 6.4 mm at 123°, before the fat
    # in front of the knee was kept off bone).
    patella = tissue.bone_names.index("patella")
    assert count[patella] == 0
    flex(tissue, 0.3)
    assert np.degrees(tissue.knee_angle) > 110.0, np.degrees(tissue.knee_angle)
    r = tissue.bones_outside_skin()
    assert r["farthest_m"][patella] < 2.5e-3 and np.isfinite(r["farthest_m"]).all()
    empty = rigid.bones_outside_skin()
    assert empty["vertices_over_1mm"].shape == (0,) and empty["farthest_m"].shape == (0,)


def test_set_excitation_single(rigid: Simulation) -> None:
    rigid.set_excitation("semimembranosus", 0.25)
    e = rigid.excitations
    i = rigid.muscle_names.index("semimembranosus")
    assert e[i] == 0.25
    assert np.count_nonzero(e) == 1


def test_set_excitations_with_dict(rigid: Simulation) -> None:
    rigid.set_excitations({"semitendinosus": 0.5, "vastus_lateralis": 0.125})
    names = rigid.muscle_names
    e = rigid.excitations
    assert e[names.index("semitendinosus")] == 0.5
    assert e[names.index("vastus_lateralis")] == 0.125
    assert np.count_nonzero(e) == 2
    # A dict only changes the muscles it names.
    rigid.set_excitations({"semitendinosus": 0.0})
    assert np.count_nonzero(rigid.excitations) == 1


def test_set_excitations_with_array(rigid: Simulation) -> None:
    n = len(rigid.muscle_names)
    values = np.linspace(0.0, 1.0, n)
    rigid.set_excitations(values)
    assert np.array_equal(rigid.excitations, values)
    rigid.set_excitations(np.full(n, 0.5, dtype=np.float32))
    assert np.array_equal(rigid.excitations, np.full(n, 0.5))
    rigid.set_excitations([0.25] * n)
    assert np.array_equal(rigid.excitations, np.full(n, 0.25))
    rigid.set_excitations(values[::-1])  # non-contiguous view
    assert np.array_equal(rigid.excitations, values[::-1])


def test_hamstrings_flex_the_knee(rigid: Simulation) -> None:
    assert rigid.knee_angle < 0.1
    flex(rigid, 0.5)
    assert rigid.knee_angle > 0.5, f"knee at {rigid.knee_angle:.3f} rad after 0.5 s of hamstrings"


def test_compliant_tendons_flex_the_knee_and_stretch(rigid: Simulation) -> None:
    compliant = Simulation.phantom(tissue=False, tendon="compliant")
    flex(compliant, 0.5)
    flex(rigid, 0.5)
    assert compliant.knee_angle > 0.5, f"knee at {compliant.knee_angle:.3f} rad"
    fibres = compliant.fibre_lengths
    assert np.all(np.isfinite(fibres))
    # The loaded tendons take up length the rigid model gives the fibres.
    assert not np.array_equal(fibres, rigid.fibre_lengths)


def test_models_switch_on_a_running_simulation(rigid: Simulation) -> None:
    assert (rigid.muscle_model, rigid.tendon) == ("hill", "rigid")
    flex(rigid, 0.2)
    angle, fibres = rigid.knee_angle, rigid.fibre_lengths
    rigid.tendon = "compliant"
    assert rigid.tendon == "compliant"
    # The pose stays; the loaded fibres give the tendons their stretch at once.
    assert rigid.knee_angle == angle
    assert not np.array_equal(rigid.fibre_lengths, fibres)
    rigid.muscle_model = "spring"
    assert rigid.muscle_model == "spring"
    rigid.step(0.001, n=50)
    assert math.isfinite(rigid.knee_angle)
    with pytest.raises(InvalidInputError, match="tendon"):
        rigid.tendon = "elastic"
    with pytest.raises(InvalidInputError, match="muscle_model"):
        rigid.muscle_model = "hil"
    # A refused value changes nothing.
    assert (rigid.muscle_model, rigid.tendon) == ("spring", "compliant")


def test_one_muscle_takes_its_own_tendon(rigid: Simulation) -> None:
    flex(rigid, 0.1)
    names = rigid.muscle_names
    st = names.index("semitendinosus")
    fibres = rigid.fibre_lengths
    rigid.set_muscle_tendon("semitendinosus", "compliant")
    tendons = rigid.muscle_tendons
    assert tendons[st] == "compliant"
    assert all(t == "rigid" for i, t in enumerate(tendons) if i != st)
    assert rigid.tendon == "rigid"  # the default stays
    # Only its fibre moved: the others keep their state.
    changed = np.flatnonzero(rigid.fibre_lengths != fibres)
    assert changed.tolist() == [st]
    with pytest.raises(myoslice.UnknownNameError, match="semitendinosus"):
        rigid.set_muscle_tendon("semitendinosis", "rigid")
    with pytest.raises(InvalidInputError, match="tendon"):
        rigid.set_muscle_tendon("semitendinosus", "elastic")
    assert rigid.muscle_tendons == tendons
    # The global switch gives every muscle the same tendon again.
    rigid.tendon = "rigid"
    assert set(rigid.muscle_tendons) == {"rigid"}


def test_set_knee(rigid: Simulation) -> None:
    rigid.set_knee(0.8)
    assert rigid.knee_angle == pytest.approx(0.8, abs=1e-6)
    assert rigid.knee_velocity == 0.0
    rigid.set_knee(0.4, velocity=1.5)
    assert rigid.knee_angle == pytest.approx(0.4, abs=1e-6)
    assert rigid.knee_velocity == pytest.approx(1.5)


# --- determinism and checkpoints -----------------------------------------------------


def _scripted_run(sim: Simulation) -> dict[str, object]:
    sim.set_excitations({"semimembranosus": 0.7, "vastus_lateralis": 0.2})
    sim.step(0.001, n=80)
    sim.set_excitation("biceps_femoris_short", 1.0)
    for _ in range(40):
        sim.step(0.001)
    return snapshot(sim)


@pytest.mark.parametrize("with_tissue", [False, True], ids=["rigid", "tissue"])
def test_determinism_two_simulations(with_tissue: bool) -> None:
    a = Simulation.phantom(tissue=with_tissue)
    b = Simulation.phantom(tissue=with_tissue)
    assert_identical(snapshot(a), snapshot(b))
    ra, rb = _scripted_run(a), _scripted_run(b)
    assert_identical(ra, rb)
    assert a.knee_angle == b.knee_angle


@pytest.mark.parametrize("with_tissue", [False, True], ids=["rigid", "tissue"])
def test_state_round_trip_is_bit_identical(request: pytest.FixtureRequest, with_tissue: bool) -> None:
    sim: Simulation = request.getfixturevalue("tissue" if with_tissue else "rigid")
    flex(sim, 0.05)
    checkpoint = sim.state()
    assert isinstance(checkpoint, State)
    assert isinstance(checkpoint.time, float)
    assert checkpoint.time == sim.time
    before = snapshot(sim)

    def run() -> tuple[list[float], dict[str, object]]:
        angles = []
        for _ in range(100):
            sim.step(0.001)
            angles.append(sim.knee_angle)
        return angles, snapshot(sim)

    angles_1, end_1 = run()
    sim.set_state(checkpoint)
    assert sim.time == checkpoint.time
    assert sim.state().time == checkpoint.time
    assert_identical(snapshot(sim), before)
    angles_2, end_2 = run()
    assert angles_1 == angles_2
    assert_identical(end_1, end_2)


def test_state_is_independent_of_later_steps(rigid: Simulation) -> None:
    checkpoint = rigid.state()
    t = checkpoint.time
    flex(rigid, 0.1)
    assert checkpoint.time == t
    assert rigid.time > t


# --- tissue metrics ------------------------------------------------------------------


def test_tissue_arrays_with_tissue(tissue: Simulation) -> None:
    flex(tissue, 0.3)
    n_fat = tissue.n_fat_elements
    assert n_fat > 0
    for name in PER_FAT_F32:
        a = getattr(tissue, name)
        assert isinstance(a, np.ndarray) and a.dtype == np.float32, name
        assert a.shape == (n_fat,), name
        assert np.all(np.isfinite(a)), name
    assert np.all(tissue.deformation_degree >= 0.0)
    mvr = tissue.muscle_volume_ratio
    assert mvr.dtype == np.float32 and mvr.shape == (len(tissue.muscle_names),)
    assert np.all(np.isfinite(mvr)) and np.all(mvr > 0.0)
    assert float(np.abs(tissue.area_change).max()) > 0.0, "the skin did not deform after flexion"


def test_tissue_elements_do_not_invert(tissue: Simulation) -> None:
    flex(tissue, 0.3)
    ratio = tissue.volume_ratio
    inverted = int(np.count_nonzero(ratio <= 0.0))
    assert inverted == 0, (
        f"{inverted} of {ratio.size} fat elements inverted (volume ratio <= 0, min {ratio.min():.3f}) "
        "after 0.3 s of hamstring flexion"
    )


def test_folds_and_the_guard_tally_are_reported(tissue: Simulation, rigid: Simulation) -> None:
    assert tissue.folded_elements == 0 and tissue.guard_tally == {"updates": 0, "vertices": 0}
    checkpoint = tissue.state()
    flex(tissue, 0.3)
    folded, tally = tissue.folded_elements, tissue.guard_tally
    assert isinstance(folded, int) and 0 <= folded < tissue.n_fat_elements
    assert tally["updates"] <= tally["vertices"] and (tally["updates"] == 0) == (tally["vertices"] == 0)
    # The tally goes with the checkpoint.
    tissue.set_state(checkpoint)
    assert tissue.guard_tally == {"updates": 0, "vertices": 0}
    flex(rigid, 0.05)
    assert rigid.folded_elements == 0 and rigid.guard_tally == {"updates": 0, "vertices": 0}


def test_tissue_rate_and_iterations_are_applied(tissue: Simulation) -> None:
    # Fewer shape-matching iterations leave the fat less relaxed: another skin.
    fewer = Simulation.phantom(tissue_iterations=1)
    for sim in (tissue, fewer):
        sim.reset_timers()
        flex(sim, 0.11)
    skin, _ = tissue.surface("skin")
    skin_fewer, _ = fewer.surface("skin")
    assert skin.shape == skin_fewer.shape
    assert float(np.abs(skin - skin_fewer).max()) > 1e-5
    # A third of the rate: a third of the updates (at 33, 67 and 100 ms; at 100 ms).
    slower = Simulation.phantom(tissue_rate_hz=10.0)
    slower.reset_timers()
    flex(slower, 0.11)
    assert (tissue.timers["tissue_updates"], slower.timers["tissue_updates"]) == (3, 1)


def test_tissue_arrays_without_tissue(rigid: Simulation) -> None:
    flex(rigid, 0.05)
    for name in (*PER_FAT_F32, "muscle_volume_ratio"):
        a = getattr(rigid, name)
        assert isinstance(a, np.ndarray) and a.dtype == np.float32, name
        assert a.shape == (0,), name
    assert rigid.n_fat_elements > 0
