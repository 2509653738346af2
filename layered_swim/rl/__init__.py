"""The SWIM-style residual policy's environment (``env.py``), its observation (``observation.py``)
and reward (``reward.py``). Needs the ``[rl]`` extra (gymnasium, torch).

Registered Gymnasium ids: ``layered_swim/FrontCrawlGoal-v0``, ``layered_swim/BreaststrokeGoal-v0`` and
``layered_swim/ButterflyGoal-v0``
(SWIM's goal reaching in its small pool; keyword arguments as ``SwimGoalEnv``'s).
"""
from __future__ import annotations

from layered_swim.config import ConfigError

RL_INSTALL = "pip install -e '.[rl]'"

try:
    import gymnasium
except ImportError:           # one line for the user, not a traceback
    raise ConfigError(f"the RL environment needs the [rl] extra: {RL_INSTALL}") from None

for _id, _stroke in (("layered_swim/FrontCrawlGoal-v0", "front_crawl"),
                     ("layered_swim/BreaststrokeGoal-v0", "breaststroke"),
                     ("layered_swim/ButterflyGoal-v0", "butterfly")):
    if _id not in gymnasium.registry:
        gymnasium.register(id=_id, entry_point="layered_swim.rl.env:SwimGoalEnv", kwargs={"stroke": _stroke})
