"""Every bad input raises the documented exception class, with a useful message."""

from __future__ import annotations

import json
import math
import os
import pickle
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import myoslice
from myoslice import (
    InvalidInputError,
    ModelFileError,
    MyoSliceError,
    RendererUnavailableError,
    Simulation,
    SimulationError,
    UnknownNameError,
)

# --- the hierarchy -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("cls", "builtins"),
    [
        (InvalidInputError, (ValueError,)),
        (UnknownNameError, (InvalidInputError, ValueError, KeyError)),
        (ModelFileError, (OSError,)),
        (SimulationError, (RuntimeError,)),
        (RendererUnavailableError, (RuntimeError,)),
    ],
)
def test_hierarchy(cls: type[Exception], builtins: tuple[type[Exception], ...]) -> None:
    assert issubclass(cls, MyoSliceError)
    for b in builtins:
        assert issubclass(cls, b), f"{cls.__name__} should be a {b.__name__}"
    assert cls.__module__ == "myoslice.errors"
    assert getattr(myoslice, cls.__name__) is cls


def test_unknown_name_error_prints_its_plain_message() -> None:
    e = UnknownNameError("unknown muscle 'x' (did you mean 'y'?)")
    assert str(e) == "unknown muscle 'x' (did you mean 'y'?)"  # KeyError would add quotes
    assert e.args == ("unknown muscle 'x' (did you mean 'y'?)",)


@pytest.mark.parametrize(
    "cls", [InvalidInputError, UnknownNameError, ModelFileError, SimulationError, RendererUnavailableError]
)
def test_errors_pickle(cls: type[Exception]) -> None:
    e = pickle.loads(pickle.dumps(cls("message")))
    assert type(e) is cls and str(e) == "message"


# --- names ---------------------------------------------------------------------------


def test_unknown_muscle(rigid: Simulation) -> None:
    with pytest.raises(UnknownNameError) as info:
        rigid.set_excitation("semitendinosis", 0.5)
    e = info.value
    assert isinstance(e, MyoSliceError)
    assert isinstance(e, InvalidInputError)
    assert isinstance(e, ValueError)
    assert isinstance(e, KeyError)
    assert "did you mean" in str(e)
    assert "semitendinosus" in str(e)
    assert not str(e).startswith(("'", '"'))


def test_unknown_muscle_caught_as_key_error(rigid: Simulation) -> None:
    with pytest.raises(KeyError):
        rigid.set_excitation("no_such_muscle", 0.5)


def test_dict_with_unknown_muscle_changes_nothing(rigid: Simulation) -> None:
    rigid.set_excitation("semitendinosus", 0.25)
    before = rigid.excitations
    with pytest.raises(UnknownNameError) as info:
        rigid.set_excitations({"semitendinosus": 0.5, "vastus_lateralis_x": 0.1})
    assert "vastus_lateralis_x" in str(info.value)
    assert np.array_equal(rigid.excitations, before)


# --- excitation values ---------------------------------------------------------------


@pytest.mark.parametrize("value", [1.5, -0.1, math.nan, math.inf])
def test_bad_excitation_value(rigid: Simulation, value: float) -> None:
    with pytest.raises(InvalidInputError):
        rigid.set_excitation("semitendinosus", value)
    with pytest.raises(InvalidInputError):
        rigid.set_excitations({"semitendinosus": value})
    values = np.zeros(len(rigid.muscle_names))
    values[0] = value
    with pytest.raises(InvalidInputError):
        rigid.set_excitations(values)
    assert np.count_nonzero(rigid.excitations) == 0


WRONG_SHAPES: dict[str, Callable[[int], tuple[int, ...]]] = {
    "scalar": lambda n: (),
    "empty": lambda n: (0,),
    "n-1": lambda n: (n - 1,),
    "n+1": lambda n: (n + 1,),
    "2xn": lambda n: (2, n),
    "nx1": lambda n: (n, 1),
}


@pytest.mark.parametrize("shape", WRONG_SHAPES.values(), ids=WRONG_SHAPES.keys())
def test_excitations_array_of_wrong_shape(rigid: Simulation, shape: Callable[[int], tuple[int, ...]]) -> None:
    with pytest.raises(InvalidInputError):
        rigid.set_excitations(np.full(shape(len(rigid.muscle_names)), 0.5))
    assert np.count_nonzero(rigid.excitations) == 0


def test_excitations_of_wrong_type(rigid: Simulation) -> None:
    with pytest.raises((InvalidInputError, TypeError)):
        rigid.set_excitations("semitendinosus")
    with pytest.raises((InvalidInputError, TypeError)):
        rigid.set_excitations({"semitendinosus": "high"})  # type: ignore[dict-item]


# --- stepping ------------------------------------------------------------------------


@pytest.mark.parametrize("dt", [-0.001, 0.0, math.nan, math.inf, -math.inf])
def test_bad_dt(rigid: Simulation, dt: float) -> None:
    with pytest.raises(InvalidInputError) as info:
        rigid.step(dt)
    assert "dt" in str(info.value)
    assert rigid.time == 0.0


@pytest.mark.parametrize("n", [0, -1])
def test_bad_step_count(rigid: Simulation, n: int) -> None:
    with pytest.raises(InvalidInputError):
        rigid.step(0.001, n=n)
    assert rigid.time == 0.0


@pytest.mark.parametrize(("angle", "velocity"), [(10.0, 0.0), (math.nan, 0.0), (0.5, math.nan)])
def test_bad_set_knee(rigid: Simulation, angle: float, velocity: float) -> None:
    with pytest.raises(InvalidInputError):
        rigid.set_knee(angle, velocity)


# --- construction --------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs",
    [
        {"muscle_model": "bogus"},
        {"tendon": "bogus"},
        {"body_mass_kg": -1.0},
        {"height_m": math.nan},
        {"max_step_s": 0.0},
        {"chain_tether": -1.0},
        {"chain_tether": math.nan},
        {"chain_tether_release_n": -1.0},
        {"chain_tether_release_n": math.inf},
        {"tissue_rate_hz": 0.0},
        {"tissue_iterations": 0},
        {"tissue_iterations": -1},
    ],
    ids=lambda kw: next(iter(kw)),
)
def test_bad_phantom_option(kwargs: dict[str, object]) -> None:
    with pytest.raises(InvalidInputError):
        Simulation.phantom(**kwargs)  # type: ignore[arg-type]


def test_missing_nifti_file(tmp_path: Path) -> None:
    labels = tmp_path / "labels.json"
    labels.write_text("{}")
    with pytest.raises(ModelFileError) as info:
        Simulation.from_nifti(tmp_path / "missing.nii.gz", labels)
    assert isinstance(info.value, OSError)
    assert isinstance(info.value, MyoSliceError)
    assert "missing.nii.gz" in str(info.value)


def test_missing_label_table(tmp_path: Path) -> None:
    volume = tmp_path / "volume.nii"
    volume.write_bytes(b"")
    with pytest.raises(ModelFileError):
        Simulation.from_nifti(str(volume), str(tmp_path / "missing_labels.json"))


def test_corrupt_nifti_file(tmp_path: Path) -> None:
    volume = tmp_path / "volume.nii"
    volume.write_bytes(b"not a nifti file at all" * 20)
    labels = tmp_path / "labels.json"
    labels.write_text("{}")
    with pytest.raises(ModelFileError):
        Simulation.from_nifti(volume, labels)


def test_missing_scenario_file(tmp_path: Path) -> None:
    with pytest.raises(ModelFileError) as info:
        Simulation.from_scenario(tmp_path / "missing.toml")
    assert isinstance(info.value, OSError)


def test_scenario_with_unknown_key(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("[simulation]\nduration_s = 0.1\nbogus_key_xyz = 3\n")
    with pytest.raises(MyoSliceError) as info:
        Simulation.from_scenario(path)
    assert "bogus_key_xyz" in str(info.value)


def test_scenario_that_is_not_toml(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("this is [not toml\n")
    with pytest.raises(MyoSliceError):
        Simulation.from_scenario(str(path))


# --- surfaces, checkpoints and rendering ---------------------------------------------


def test_unknown_surface_layer(rigid: Simulation) -> None:
    with pytest.raises(InvalidInputError) as info:
        rigid.surface("cartilage")
    assert "cartilage" in str(info.value)


def test_set_state_needs_a_state(rigid: Simulation) -> None:
    with pytest.raises(TypeError):
        rigid.set_state("not a state")  # type: ignore[arg-type]


def test_bad_render_color(rigid: Simulation) -> None:
    # Options are checked before any GPU is looked for, so this holds without one.
    with pytest.raises(InvalidInputError) as info:
        rigid.render(64, 64, color="rainbow")
    assert "rainbow" in str(info.value)


def test_bad_render_camera(rigid: Simulation) -> None:
    with pytest.raises(InvalidInputError):
        rigid.render(64, 64, camera="upside_down")


def test_bad_render_size(rigid: Simulation) -> None:
    with pytest.raises(InvalidInputError):
        rigid.render(0, 0)


def test_bad_chain_tether_is_named() -> None:
    with pytest.raises(InvalidInputError, match="chain_tether"):
        Simulation.phantom(tissue=False, chain_tether=-1.0)
    with pytest.raises(InvalidInputError, match="chain_tether_release_n"):
        Simulation.phantom(tissue=False, chain_tether_release_n=-1.0)


VISIBLE_HUMAN = Path(__file__).resolve().parents[3] / "shared" / "data" / "visible-human"


def _visible_human() -> tuple[Path, Path]:
    """The Visible Human volume and label table; never a silent pass when absent."""
    volume = VISIBLE_HUMAN / "vhf_left_leg_labels.nii.gz"
    if not volume.exists():
        if os.environ.get("MYOSLICE_ALLOW_MISSING_DATA") != "1":
            pytest.fail(f"{volume} is absent (set MYOSLICE_ALLOW_MISSING_DATA=1 to skip on purpose)")
        pytest.skip(f"{volume} is absent")
    return volume, VISIBLE_HUMAN / "vhf_left_leg_labels.json"


def _itk_snap(table: Path, path: Path, rename: Callable[[str], str], extra: str = "") -> Path:
    """The table's labels as an ITK-SNAP label description file, each name as `rename`
    says (background and fat by their usual names)."""
    labels = json.loads(table.read_text())["labels"]
    lines = ["# ITK-SnAP Label Description File"]
    for key, rec in sorted(labels.items(), key=lambda kv: int(kv[0])):
        name = {"background": "Clear Label", "fat": "Subcutaneous fat"}.get(rec["name"]) or rename(rec["name"])
        lines.append(f'{key} 10 20 30 1 1 1 "{name}"')
    path.write_text("\n".join(lines) + "\n" + extra)
    return path


def test_a_segmentation_tools_label_list_builds_the_leg_and_unknown_names_are_refused(tmp_path: Path) -> None:
    """An ITK-SNAP label file with people's names builds the same leg as our own label
    table; a label no structure is known by is refused unless asked otherwise."""
    volume, table = _visible_human()
    itk = _itk_snap(
        table,
        tmp_path / "leg-labels.txt",
        lambda n: "Left " + n.replace("_", " "),
        '99 1 1 1 1 1 1 "Popliteal artery"\n',
    )
    with pytest.raises(MyoSliceError) as info:
        Simulation.from_nifti(volume, itk, tissue=False)
    assert "label 99 'Popliteal artery'" in str(info.value)
    with pytest.raises(InvalidInputError):
        Simulation.from_nifti(volume, itk, unmapped="bogus", tissue=False)
    # A NIfTI names none of its labels: the label file is needed.
    with pytest.raises(MyoSliceError) as info:
        Simulation.from_nifti(volume, tissue=False)
    assert "names none of its labels" in str(info.value)
    ours = Simulation.from_nifti(volume, table, tissue=False)
    theirs = Simulation.from_nifti(volume, itk, unmapped="fat", tissue=False)
    assert theirs.muscle_names == ours.muscle_names
    assert theirs.n_fat_elements == ours.n_fat_elements


def test_from_file_reads_by_content_with_the_users_own_names(tmp_path: Path) -> None:
    """`from_file` tells a scenario from a volume by content; a names file maps the
    user's names (winning over the synonyms) and adds a muscle the catalogue does not
    know, which is built from its volume and length with a warning."""
    volume, table = _visible_human()
    renamed = {"gracilis": "GRA-x", "sartorius": "Strap muscle"}
    itk = _itk_snap(table, tmp_path / "leg-labels.txt", lambda n: renamed.get(n, n))
    names = tmp_path / "my-names.toml"
    names.write_text(
        '[map]\n"GRA-x" = "gracilis"\n\n'
        '[structure.strap_muscle]\nkind = "muscle"\norigin = "hip_bone"\ninsertion = "tibia"\nnames = ["Strap muscle"]\n'
    )
    with pytest.raises(MyoSliceError) as info:
        Simulation.from_file(volume, itk, tissue=False)
    assert "'GRA-x'" in str(info.value) and "'Strap muscle'" in str(info.value)
    with pytest.warns(UserWarning, match="muscle 'strap_muscle' has no entry in the muscle catalogue"):
        sim = Simulation.from_file(volume, itk, names=names, tissue=False)
    assert "gracilis" in sim.muscle_names and "strap_muscle" in sim.muscle_names
    assert "sartorius" not in sim.muscle_names
    assert [w.split("'")[1] for w in sim.warnings] == ["strap_muscle"]
    with pytest.raises(ModelFileError, match="names file"):
        Simulation.from_file(volume, itk, names=tmp_path / "absent.toml")
    bad = tmp_path / "bad-names.toml"
    bad.write_text('[map]\n"GRA-x" = "kidney"\n')
    with pytest.raises(ModelFileError, match='map."GRA-x" = "kidney"'):
        Simulation.from_file(volume, itk, names=bad)
    # A scenario, whatever its name, is a scenario; it takes no other argument.
    scenario = tmp_path / "knee.cfg"
    scenario.write_text('[model]\nsource = "phantom"\n[simulation]\nduration_s = 0.01\n[tissue]\nenabled = false\n')
    sc = Simulation.from_file(scenario)
    assert sc.warnings == [] and sc.n_fat_elements > 0
    with pytest.raises(InvalidInputError, match="scenario"):
        Simulation.from_file(scenario, tissue=False)
