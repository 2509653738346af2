"""``checkpoint.pt``: everything a training run needs to go on (``--resume``), written so that
torch's safe unpickler reads it all, and read back with every part checked before use (it may
be a file someone handed over)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from layered_swim.config import ConfigError
from layered_swim.rl.buffer import EpisodeData
from layered_swim.rl.checks import check_keys, check_tensors, is_count, read_weights

# 2: the buffer's arrays as tensors, so torch's safe unpickler reads it all; 3: the spec's buffer.policy
# renamed buffer.eviction.
CHECKPOINT_FORMAT = 3
CHECKPOINT_KEYS = ("format", "spec", "model", "optimiser", "normaliser", "epoch", "samples", "wall_s", "rng",
                   "generator", "buffer")
MAX_CHECKPOINT_BYTES = 4 * 2**30  # 64 buffered episodes are tens of MB; the largest buffer allowed nears this
EPISODE_ARRAYS = ("obs", "actions", "log_probs", "rewards", "final_obs")
EPISODE_KEYS = (*EPISODE_ARRAYS, "truncated", "epoch")
ADAM_STATE = ("step", "exp_avg", "exp_avg_sq")     # torch.optim.Adam's per parameter (amsgrad off)
MAX_COUNT = 2**62                 # epochs, samples: far past any run, and an int64 still


def read_checkpoint(path: Path) -> dict:
    state = read_weights(path, MAX_CHECKPOINT_BYTES, "not a checkpoint this version reads: an older version's, or "
                                                     "one holding more than tensors and plain data ({kind}); "
                                                     "start over with --overwrite")
    version = state.get("format") if isinstance(state, dict) else None
    if type(version) is not int or version > CHECKPOINT_FORMAT:
        raise ConfigError(f"{path}: not a layered-swim checkpoint (format {CHECKPOINT_FORMAT})")
    if version < CHECKPOINT_FORMAT:
        raise ConfigError(f"{path}: written by an older version; start over with --overwrite")
    return check_keys(state, CHECKPOINT_KEYS, "checkpoint", path)


def adam_state(value, params: list[torch.Tensor], source) -> dict:
    """The optimiser's per-parameter state: for parameters of ours (by index), each a step count
    and two moments of the parameter's shape, finite, neither the count nor the second below 0."""
    state = check_keys(value, ("state", "param_groups"), "optimiser", source)["state"]
    if not (isinstance(state, dict) and all(is_count(k, 0, len(params) - 1) for k in state)):
        raise ConfigError(f"{source}: optimiser state must be keyed by the model's {len(params)} parameter indices")
    for index, moments in state.items():
        like = dict(zip(ADAM_STATE, (torch.zeros(()), params[index], params[index])))
        check_tensors(moments, like, f"optimiser state {index}", source)
        if moments["step"] < 0 or (moments["exp_avg_sq"] < 0).any():
            raise ConfigError(f"{source}: optimiser state {index} has a negative step or second moment")
    return state


def same_layout(value, ours) -> bool:
    """``value`` has ``ours``'s layout: the same keys and strings, ints (up to 128 bits) where it has ints."""
    if isinstance(ours, dict):
        return isinstance(value, dict) and value.keys() == ours.keys() and all(
            same_layout(value[k], v) for k, v in ours.items())
    if isinstance(ours, str):
        return type(value) is str and value == ours
    return type(value) is int and 0 <= value < 2**128


def numpy_rng(state, source) -> np.random.Generator:
    """The episode seeds' and eviction's generator, from its saved state (PCG64's 128-bit ints)."""
    rng = np.random.default_rng()
    name = type(rng.bit_generator).__name__
    if not same_layout(state, rng.bit_generator.state):
        raise ConfigError(f"{source}: rng is not a {name} generator's state")
    try:
        rng.bit_generator.state = state
    except (ValueError, OverflowError):       # a field beyond its C type
        raise ConfigError(f"{source}: rng holds an out-of-range {name} state") from None
    return rng


def torch_generator(state, source) -> torch.Generator:
    """The minibatch order's generator, from its saved state."""
    generator = torch.Generator()
    like = generator.get_state()
    if not (isinstance(state, torch.Tensor) and state.dtype == like.dtype and state.shape == like.shape):
        raise ConfigError(f"{source}: generator must be a torch generator's state ({like.numel()} bytes)")
    try:
        generator.set_state(state)
    except RuntimeError:      # torch's own check of the Mersenne twister's state
        raise ConfigError(f"{source}: generator holds an invalid state") from None
    return generator


def buffer_episodes(value, n_obs: int, n_act: int, capacity: int, epoch: int, source) -> list[EpisodeData]:
    """The buffer: at most ``capacity`` episodes collected before ``epoch``, each T >= 1 steps of
    finite float32/64 arrays of the model's sizes. Their sizes together may not pass the file's
    cap (tensors may share one storage: a small file could otherwise claim terabytes)."""
    if not (isinstance(value, list) and len(value) <= capacity):
        raise ConfigError(f"{source}: buffer must be a list of at most {capacity} episodes")
    episodes, budget = [], MAX_CHECKPOINT_BYTES
    for k, item in enumerate(value):
        arrays = [check_keys(item, EPISODE_KEYS, f"buffer episode {k}", source)[name] for name in EPISODE_ARRAYS]
        if not all(isinstance(a, torch.Tensor) and a.layout == torch.strided
                   and a.dtype in (torch.float32, torch.float64) for a in arrays):
            raise ConfigError(f"{source}: buffer episode {k}: {', '.join(EPISODE_ARRAYS)} must be float tensors")
        budget -= sum(a.numel() * a.element_size() for a in arrays)
        if budget < 0:
            raise ConfigError(f"{source}: the buffer's arrays add up to more than a checkpoint may hold")
        rewards = arrays[EPISODE_ARRAYS.index("rewards")]
        steps = rewards.shape[0] if rewards.dim() == 1 else 0
        shapes = [(steps, n_obs), (steps, n_act), (steps,), (steps,), (n_obs,)]
        if steps < 1 or [tuple(a.shape) for a in arrays] != shapes:
            raise ConfigError(f"{source}: buffer episode {k}: expected T >= 1 steps of {n_obs} observations, "
                              f"{n_act} actions, a log-probability and a reward, and {n_obs} final observations")
        if not all(torch.isfinite(a).all() for a in arrays):
            raise ConfigError(f"{source}: buffer episode {k} holds NaN or infinite values")
        if not (type(item["truncated"]) is bool and is_count(item["epoch"], 0, epoch - 1)):
            raise ConfigError(f"{source}: buffer episode {k}: truncated must be true or false, epoch in 0..{epoch - 1}")
        episodes.append(EpisodeData(*(a.detach().numpy() for a in arrays), item["truncated"], item["epoch"]))
    return episodes


def episode_state(e: EpisodeData) -> dict:
    """An episode as the safe unpickler reads it: its arrays as tensors (copies, the same bits: Ray's are
    read-only)."""
    return {**{name: torch.tensor(getattr(e, name)) for name in EPISODE_ARRAYS}, "truncated": e.truncated,
            "epoch": e.epoch}
