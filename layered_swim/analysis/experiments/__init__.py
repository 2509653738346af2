"""The papers' experiments as commands (``layered-swim experiment NAME``); see ``runner.py``."""
from __future__ import annotations

from layered_swim.analysis.experiments import (
    current_sweep,
    density_sweep,
    hand_force,
    layers_in_current,
    palm_rule,
    perturbation,
    robustness,
    swim_generalisation,
    swim_table,
    turn,
)
from layered_swim.config import ConfigError

EXPERIMENTS = {m.NAME: m for m in (hand_force, turn, palm_rule, layers_in_current, density_sweep, current_sweep,
                                   perturbation, swim_table, swim_generalisation, robustness)}


def experiment(name: str):
    try:
        return EXPERIMENTS[name]
    except KeyError:
        raise ConfigError(f"unknown experiment '{name}' (available: {', '.join(EXPERIMENTS)})") from None
