"""What the MuJoCo and OpenSim one-hinge knees share: the 16 muscles with their Hill parameters
(read from assets/muscles.toml), the fixed moment arms, the Dempster shank and the task.

Everything here is plain Python (tomllib, Python >= 3.11); the simulators are imported by the
scripts that use them.
"""
from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
CATALOGUE = Path(os.environ.get("MYOSLICE_MUSCLES", REPO / "assets" / "muscles.toml"))

# The 16 muscles of myoslice's `knee_hinge_16` case, in a fixed order.
MUSCLES = [
    "semitendinosus", "semimembranosus", "biceps_femoris_long", "biceps_femoris_short", "gracilis",
    "sartorius", "gastrocnemius_medial", "gastrocnemius_lateral", "rectus_femoris", "vastus_lateralis",
    "vastus_medialis", "vastus_intermedius", "tensor_fasciae_latae", "popliteus", "plantaris",
    "adductor_magnus",
]
# Constant moment arms by catalogue group (m).
MOMENT_ARM = {"flexor": 0.035, "extensor": 0.045, "other": 0.010}
# Muscles the catalogue has no numbers for (popliteus, plantaris) get these (the brief's defaults).
FALLBACK = {
    "max_isometric_force_n": 100.0,
    "optimal_fibre_length_m": 0.05,
    "tendon_slack_length_m": 0.05,
    "pennation_deg": 0.0,
    "max_contraction_velocity": 10.0,
}

# Shank and foot after Dempster (Winter, Table 4.1), 60 kg, 1.65 m, as myoslice's
# body::segments::shank_and_foot.
BODY_MASS = 60.0
HEIGHT = 1.65
SHANK_MASS = 0.061 * BODY_MASS  # 3.66 kg
SHANK_LENGTH = 0.246 * HEIGHT  # 0.4059 m, knee to ankle
SHANK_COM = 0.606 * SHANK_LENGTH  # from the knee
SHANK_I_TRANSVERSE = SHANK_MASS * (0.416 * SHANK_LENGTH) ** 2  # about the CoM
SHANK_I_LONG = 0.5 * SHANK_MASS * 0.05**2
GRAVITY = 9.81
KNEE_RANGE_DEG = (0.0, 140.0)
KNEE_DAMPING = 0.3  # N m s / rad, myoslice's SimulationConfig::knee_damping default

# Task: every flexor excited at 0.6 for 1 s from full extension, 1 ms step.
EXCITATION = 0.6
DURATION = 1.0
DT = 0.001
REPEATS = 3

# De Groote et al. (2016) activation time constants, as myoslice's HillParams::new.
TAU_ACTIVATION = 0.015
TAU_DEACTIVATION = 0.060
FIBRE_DAMPING = 0.01


@dataclass(frozen=True)
class Muscle:
    name: str
    group: str  # flexor | extensor | other
    fmax: float  # N
    lopt: float  # m
    lts: float  # m
    pennation: float  # rad
    vmax: float  # optimal fibre lengths per second
    rest_norm: float  # fibre length / optimal at full extension
    insertion_below_knee: float  # m (OpenSim path geometry only)
    defaulted: bool  # numbers came from FALLBACK

    @property
    def moment_arm(self) -> float:
        return MOMENT_ARM[self.group]

    @property
    def flexes(self) -> bool:
        """Posterior (shortens as the knee flexes): flexors, and by choice the two 'other' muscles
        (tensor fasciae latae, adductor magnus), which the task leaves passive."""
        return self.group != "extensor"

    @property
    def excited(self) -> bool:
        return self.group == "flexor"

    def mtu_length_at_rest(self) -> float:
        """Muscle-tendon length at full extension: slack tendon plus the fibre at rest_norm
        optimal lengths, with constant-thickness pennation (fibre projected on the tendon)."""
        h = self.lopt * math.sin(self.pennation)
        fibre = self.rest_norm * self.lopt
        return self.lts + math.sqrt(max(fibre * fibre - h * h, (1e-3 * self.lopt) ** 2))


def load_muscles(path: Path = CATALOGUE) -> list[Muscle]:
    if not path.is_file():
        raise SystemExit(f"muscle catalogue not found: {path} (set MYOSLICE_MUSCLES to its path)")
    with open(path, "rb") as f:
        cat = tomllib.load(f)
    default = cat.get("default", {})
    table = cat.get("muscle", {})
    out = []
    for name in MUSCLES:
        if name not in table:
            raise SystemExit(f"{path}: muscle '{name}' missing")
        m = table[name]
        group = m.get("group", "other")
        if group not in MOMENT_ARM:
            raise SystemExit(f"{path}: muscle '{name}' has unknown group '{group}'")
        defaulted = "max_isometric_force_n" not in m
        src = FALLBACK if defaulted else m

        def get(key: str) -> float:
            return float(src.get(key, FALLBACK[key]))

        out.append(Muscle(
            name=name,
            group=group,
            fmax=get("max_isometric_force_n"),
            lopt=get("optimal_fibre_length_m"),
            lts=get("tendon_slack_length_m"),
            pennation=math.radians(get("pennation_deg")),
            vmax=get("max_contraction_velocity"),
            rest_norm=float(m.get("rest_fibre_length", default.get("rest_fibre_length", 1.0))),
            insertion_below_knee=float(m.get("insertion_below_knee_m", 0.03)),
            defaulted=defaulted,
        ))
    return out


def summary(muscles: list[Muscle]) -> dict:
    return {
        "muscles": len(muscles),
        "excited": [m.name for m in muscles if m.excited],
        "defaulted": [m.name for m in muscles if m.defaulted],
    }
