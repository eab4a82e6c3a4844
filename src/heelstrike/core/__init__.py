"""Impact algebra for inert constraints (knows no walker)."""

from heelstrike.core.impact import (
    ImpactInputError,
    ImpactResult,
    admissible_projector,
    constrained_projector,
    decompose_impulse,
    decompose_velocity,
    impact,
    kinetic_energy,
)

__all__ = [
    "ImpactInputError",
    "ImpactResult",
    "admissible_projector",
    "constrained_projector",
    "decompose_impulse",
    "decompose_velocity",
    "impact",
    "kinetic_energy",
]
