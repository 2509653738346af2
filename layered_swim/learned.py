"""A learned residual in charge of a swim: the steering of a ``SwimSpec`` that names a policy
file, for the commands and analyses that run such swims. ``rl`` (the [rl] extra) is imported
only when the spec names one."""
from __future__ import annotations


def steering_for(spec):
    """``rl.policy.Steering`` for ``spec.policy`` (refused in one line if it was trained for
    another stroke); None for a swim without a policy."""
    if spec.policy is None:
        return None
    from layered_swim.rl.policy import ResidualPolicy

    return ResidualPolicy.load(spec.policy).steering(spec.stroke)
