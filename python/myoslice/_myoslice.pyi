"""Type stubs of the compiled module ``myoslice._myoslice`` (hand-written; checked with
``python -m mypy.stubtest myoslice._myoslice``).

Units are SI throughout: metres, seconds, newtons, radians. Every array property returns
a fresh copy: writing to it does not change the simulation.
"""

import os
from typing import Any, TypeAlias, TypedDict, final

import numpy as np
import numpy.typing as npt

__all__ = ["Simulation", "State", "__version__", "check_scenario", "run_scenario"]

_StrPath: TypeAlias = str | os.PathLike[str]

__version__: str

class _TissuePhases(TypedDict):
    """Seconds of the tissue updates, phase by phase, in update order."""

    muscle_shapes: float
    knee_fold: float
    first_guess: float
    shape_matching: float
    bone_sliding: float
    guard: float

class _StepTimers(TypedDict):
    """What :attr:`Simulation.timers` returns (seconds of wall-clock time, on the Rust side)."""

    calls: int
    steps: int
    tissue_updates: int
    simulated_s: float
    wall_s: float
    tissue_wall_s: float
    muscles_wall_s: float
    realtime_factor: float | None
    tissue_phases_s: _TissuePhases

class _GuardTally(TypedDict):
    """What :attr:`Simulation.guard_tally` returns."""

    updates: int
    vertices: int

class _MusclesInBone(TypedDict):
    """What :meth:`Simulation.muscles_in_bone` returns, one entry per muscle."""

    vertices_over_1mm: npt.NDArray[np.int64]
    deepest_m: npt.NDArray[np.float32]

class _OutsideSkin(TypedDict):
    """What :meth:`Simulation.muscles_outside_skin` and
    :meth:`Simulation.bones_outside_skin` return, one entry per muscle or bone."""

    vertices_over_1mm: npt.NDArray[np.int64]
    farthest_m: npt.NDArray[np.float32]

@final
class State:
    """An opaque checkpoint of a :class:`Simulation` (``Simulation.state()``)."""

    @property
    def time(self) -> float:
        """Simulated time of the checkpoint (s)."""

    def __repr__(self) -> str: ...

@final
class Simulation:
    """A muscle-driven lower limb. Build it with :meth:`phantom`, :meth:`from_nifti` or
    :meth:`from_scenario`; excite its muscles, :meth:`step` it, and read the knee, the
    muscles and the deformed tissue as numpy arrays."""

    @staticmethod
    def phantom(
        *,
        body_mass_kg: float = 60.0,
        height_m: float = 1.65,
        muscle_model: str = "hill",
        tendon: str = "rigid",
        tissue: bool = True,
        tissue_rate_hz: float = 30.0,
        tissue_iterations: int | None = None,
        initial_knee_deg: float = 0.0,
        max_step_s: float = 0.001,
        chain_tether: float | None = None,
        chain_tether_release_n: float | None = None,
        chain_contact: bool | None = None,
        muscle_contact: bool | None = None,
        fat_constraints: bool | None = None,
        voxel_mm: float | None = None,
    ) -> Simulation:
        """The built-in lower-limb phantom (no files needed).

        ``muscle_model`` is ``"hill"`` or ``"spring"``; ``tendon`` is ``"rigid"`` or
        ``"compliant"`` (the Hill units' tendons stretch, and the fibre length becomes a
        state found every step); ``tissue=False`` skips the
        deformable fat and muscle volumes (faster; the tissue arrays are then empty).
        ``tissue_rate_hz`` (tissue updates per simulated second) and
        ``tissue_iterations`` (shape-matching iterations per update; ``None``: the
        library's default) trade the tissue's smoothness for speed (the README's table).
        ``chain_tether`` (N/m) pulls each relaxed muscle's chain points toward where they
        rest on their bones (``None``: the default, 600; ``0``: the paper's free chain),
        fading out as the muscle's force rises to ``chain_tether_release_n`` (N; ``None``:
        the default, 20). ``chain_contact`` keeps muscles' chains off one another
        (``None``: the default, on); ``muscle_contact`` pushes overlapping muscle shapes
        apart after each tissue update places them, keeping their volumes (``None``: the
        default, off: it roughly doubles the tissue's time). ``fat_constraints`` holds
        each fat element's volume and keeps its corners from folding inside the tissue's
        iterations (``None``: the default, on; off: the passes one after another, which
        fold hundreds of fat elements at deep flexion).
        """

    @staticmethod
    def from_nifti(
        volume: _StrPath,
        labels: _StrPath | None = None,
        *,
        unmapped: str = "error",
        names: _StrPath | None = None,
        slice_step: int = 5,
        rays: int = 48,
        body_mass_kg: float = 60.0,
        height_m: float = 1.65,
        muscle_model: str = "hill",
        tendon: str = "rigid",
        tissue: bool = True,
        tissue_rate_hz: float = 30.0,
        tissue_iterations: int | None = None,
        initial_knee_deg: float = 0.0,
        max_step_s: float = 0.001,
        chain_tether: float | None = None,
        chain_tether_release_n: float | None = None,
        chain_contact: bool | None = None,
        muscle_contact: bool | None = None,
        fat_constraints: bool | None = None,
    ) -> Simulation:
        """A model from a label volume (NIfTI-1/-2 or NRRD; an oblique or reordered scan is
        brought into the body frame) or a PNG stack (its folder or manifest), told apart
        by content, and its label table (JSON or TOML), or a segmentation tool's label
        list (ITK-SNAP label description file, 3D Slicer colour table) whose names are
        mapped onto known structures; without ``labels``, a 3D Slicer segmentation's
        (``.seg.nrrd``) own segment names. ``unmapped`` (``"error"``, ``"fat"`` or
        ``"ignore"``) says what to do with a name none is known by; ``names`` is your own
        names file (TOML: ``[map]`` name = structure, new muscles as
        ``[structure.NAME]``). Each muscle the catalogue does not know is built from its
        volume and length, with a ``UserWarning`` (see :attr:`warnings`)."""

    @staticmethod
    def from_file(path: _StrPath, labels: _StrPath | None = None, **kwargs: Any) -> Simulation:
        """Any file myoslice reads, told apart by content: a scenario (as
        :meth:`from_scenario`; it takes no other argument) or a label volume or PNG stack
        (as :meth:`from_nifti`, with its keyword arguments)."""

    @staticmethod
    def from_scenario(path: _StrPath) -> Simulation:
        """A model from a scenario file (TOML)."""

    def step(self, dt: float = 0.001, n: int = 1) -> None:
        """Advances ``n`` steps of ``dt`` seconds (the GIL is released meanwhile)."""

    @property
    def timers(self) -> _StepTimers:
        """Wall-clock time spent in :meth:`step` on the Rust side since the build or
        :meth:`reset_timers`: ``calls``, ``steps``, ``tissue_updates`` (counts),
        ``simulated_s``, ``wall_s``, ``tissue_wall_s``, ``muscles_wall_s`` (seconds),
        ``realtime_factor`` (None before any step) and ``tissue_phases_s`` (the tissue's
        seconds by phase: ``muscle_shapes``, ``knee_fold``, ``first_guess``,
        ``shape_matching``, ``bone_sliding``, ``guard``)."""

    def reset_timers(self) -> None:
        """Starts the step timers from zero."""

    def set_excitation(self, name: str, value: float) -> None:
        """Sets one muscle's excitation in [0, 1]."""

    def set_excitations(self, values: dict[str, float] | npt.ArrayLike) -> None:
        """Sets excitations from a dict ``{name: value}`` or an array of shape
        ``(n_muscles,)`` in :attr:`muscle_names` order."""

    @property
    def excitations(self) -> npt.NDArray[np.float64]:
        """Excitation of every muscle, float64 ``(n_muscles,)``."""

    @property
    def muscle_names(self) -> list[str]:
        """Muscle names, in the order of every per-muscle array."""

    @property
    def muscle_groups(self) -> list[str]:
        """Control group of each muscle: ``"flexor"``, ``"extensor"`` or ``"other"``."""

    @property
    def muscle_tendons(self) -> list[str]:
        """Tendon model of each muscle, ``"rigid"`` or ``"compliant"`` (``muscle_names``
        order): the catalogue's ``tendon`` for that muscle, else the default."""

    def set_muscle_tendon(self, name: str, tendon: str) -> None:
        """Gives one muscle its own tendon model mid-run (``"rigid"`` or
        ``"compliant"``); the others keep theirs and their fibre states. Raises
        ``UnknownNameError`` or ``InvalidInputError`` and changes nothing on bad input."""

    @property
    def muscle_model(self) -> str:
        """The muscle model, ``"hill"`` or ``"spring"``. Settable mid-run: the pose,
        chains and activations carry over."""

    @muscle_model.setter
    def muscle_model(self, value: str) -> None: ...
    @property
    def tendon(self) -> str:
        """The Hill units' tendons, ``"rigid"`` or ``"compliant"``. Settable mid-run:
        a compliant fibre starts in static equilibrium with its tendon. Setting it gives
        every muscle that tendon; reading it gives the default (see ``muscle_tendons``)."""

    @tendon.setter
    def tendon(self, value: str) -> None: ...
    @property
    def time(self) -> float:
        """Simulated time (s)."""

    @property
    def knee_angle(self) -> float:
        """Knee flexion angle (rad)."""

    @property
    def knee_velocity(self) -> float:
        """Knee flexion velocity (rad/s)."""

    @property
    def knee_torque(self) -> float:
        """Net muscle torque about the knee (N m, positive flexing)."""

    @property
    def knee_limits(self) -> tuple[float, float]:
        """Flexion limits (rad)."""

    @property
    def activations(self) -> npt.NDArray[np.float64]:
        """Activation of every muscle, float64 ``(n_muscles,)``."""

    @property
    def forces(self) -> npt.NDArray[np.float64]:
        """Tendon force of every muscle (N), float64 ``(n_muscles,)``."""

    @property
    def fibre_lengths(self) -> npt.NDArray[np.float64]:
        """Fibre length of every muscle (m), float64 ``(n_muscles,)``."""

    @property
    def moment_arms(self) -> npt.NDArray[np.float64]:
        """Moment arm of every muscle about the knee (m, positive flexing)."""

    def surface(
        self, layer: str, *, carried: bool = False
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.uint32]]:
        """Vertices (float32 ``(N, 3)``, m) and triangles (uint32 ``(M, 3)``) of a layer
        now: ``"bone"``, ``"muscle"`` or ``"skin"``. Muscles and skin are as the last
        tissue update left them, or with ``carried`` carried with the bones from it to
        now (what the viewer draws between updates)."""

    @property
    def area_change(self) -> npt.NDArray[np.float32]:
        """A/A0 - 1 of each fat element's outer face (0 inside), float32
        ``(n_fat_elements,)``; shape ``(0,)`` without tissue."""

    @property
    def deformation_degree(self) -> npt.NDArray[np.float32]:
        """Deformation degree of each fat element (m), float32 ``(n_fat_elements,)``;
        shape ``(0,)`` without tissue."""

    @property
    def volume_ratio(self) -> npt.NDArray[np.float32]:
        """Volume over rest volume of each fat element, float32 ``(n_fat_elements,)``;
        shape ``(0,)`` without tissue."""

    @property
    def muscle_volume_ratio(self) -> npt.NDArray[np.float32]:
        """Volume over rest volume of each muscle, float32 ``(n_muscles,)``; shape
        ``(0,)`` without tissue."""

    @property
    def folded_elements(self) -> int:
        """Fat elements with a folded corner now (a corner Jacobian at or below zero,
        ParaView's test of a valid hexahedron); 0 without tissue."""

    @property
    def warnings(self) -> list[str]:
        """What the build could not take from the muscle catalogue: one line per muscle
        whose parameters came from its volume and length."""

    @property
    def guard_tally(self) -> _GuardTally:
        """How often the tissue's validity guard stepped in since the build:
        ``updates`` (tissue updates it moved fat in) and ``vertices`` (fat vertices it
        moved, summed); zeros without tissue. Part of a checkpoint."""

    def muscles_in_bone(self) -> _MusclesInBone:
        """How far each muscle's surface reaches into bone now, in :attr:`muscle_names`
        order: ``vertices_over_1mm`` (int64, vertices more than 1 mm inside a bone) and
        ``deepest_m`` (float32, m); empty arrays without tissue. Exact (a tree query per
        vertex near a bone): tens of milliseconds, for checks rather than every frame."""

    def audit(self) -> dict[str, Any] | None:
        """Every soundness check of the tissue now, measured as a user's tools do: a dict
        shaped as ``summary.json``'s ``audit`` (``folded_fat``: hexahedra with a corner
        Jacobian at or below zero; ``fat_under_half_volume``; ``min_fat_volume_ratio``;
        ``muscles_out_of_skin`` and ``bones_out_of_skin``: ``{vertices_over_1mm,
        farthest_m}``, None where the skin cannot be closed; ``muscles_in_bone`` and
        ``muscles_in_muscles``: ``{vertices_over_1mm, deepest_m}``; ``skin_crossings``;
        ``skin_in_contact_m2``: area of skin touching skin, each side counted, None where
        the skin cannot be closed;
        ``muscle_volume_ratio``: [smallest, largest]; ``fat_off_rest_m``; ``finite``).
        None without tissue. Exact: about a second on a whole leg."""

    def muscles_outside_skin(self) -> _OutsideSkin:
        """How far each muscle's surface reaches out through the skin now, in
        :attr:`muscle_names` order: ``vertices_over_1mm`` (int64, vertices more than 1 mm
        outside the skin) and ``farthest_m`` (float32, m); empty arrays without tissue
        (or where the skin cannot be closed into a mesh).
        Exact (the skin closed at both ends, a tree query per muscle vertex): tens of
        milliseconds, for checks rather than every frame."""

    def bones_outside_skin(self) -> _OutsideSkin:
        """How far each bone's surface reaches out through the skin now, in
        :attr:`bone_names` order, as :meth:`muscles_outside_skin` per bone; empty arrays
        without tissue."""

    @property
    def bone_names(self) -> list[str]:
        """Bone names, in the order of :meth:`bones_outside_skin`."""

    @property
    def n_fat_elements(self) -> int:
        """Number of fat elements (hexahedra)."""

    def set_knee(self, angle: float, velocity: float = 0.0) -> None:
        """Puts the knee at ``angle`` (rad) with flexion ``velocity`` (rad/s)."""

    def state(self) -> State:
        """A checkpoint of the whole dynamic state, the muscle and tendon models included."""

    def set_state(self, state: State) -> None:
        """Restores a checkpoint taken from this simulation."""

    def render(
        self,
        width: int = 640,
        height: int = 480,
        *,
        color: str = "area",
        camera: str = "oblique",
    ) -> npt.NDArray[np.uint8]:
        """Renders the leg off-screen: uint8 ``(height, width, 3)``.

        ``color``: ``"area"``, ``"degree"`` or ``"none"``; ``camera``: ``"front"``,
        ``"side"``, ``"back"``, ``"medial"`` or ``"oblique"``. Raises
        :class:`~myoslice.errors.RendererUnavailableError` when no GPU adapter exists.
        """

    def __repr__(self) -> str: ...


def run_scenario(
    path: _StrPath, out: _StrPath, *, text: str | None = None, reuse_model: bool = False
) -> dict[str, Any]:
    """Runs a scenario to its end into the folder ``out`` (``timeseries.csv``,
    ``summary.json``, and the VTU series and GLB its ``[output]`` asks for), as
    ``myoslice run`` does, and returns the summary as a dict. With ``text``, the scenario is
    that TOML text and ``path`` only places its relative files and names it in errors.
    With ``reuse_model``, what was built for the last scenario run so in this process is
    reused when the model (source, files, slicing) is the same: its lattice, and the whole
    simulation when the settings are the same too (only schedules and muscle factors
    differ). The same bits, without the build's cost. The GIL is released while it
    runs."""

def check_scenario(path: _StrPath, *, text: str | None = None, build: bool = False) -> None:
    """Reads and checks a scenario (every field, range and file, and the simulation's
    settings) without building it: raises what :func:`run_scenario` would raise before its
    build. With ``build``, also builds its model (reusing what was built as
    ``reuse_model`` does) so that the muscle and group names of ``[excitation]`` and
    ``[muscle.NAME]`` are checked too."""
