"""Run many independent simulations in parallel, each result cached by its configuration.

A job is a JSON-able configuration dict and a task, a module-level function (picklable) from
configuration to a JSON-able result. The cache key is a hash of the task's name, the
configuration, the task's own module and the package's other source (so an edited simulator
never serves stale results; modules that only draw or write results are left out).
Configurations that depend on files people edit carry those files' hashes (``file_sha256``). A
re-run computes only the keys missing from the cache; results are saved as each job finishes, so
an interrupted sweep keeps what it had done. Every job is seeded and deterministic, so the number
of workers never changes a result.
"""
from __future__ import annotations

import hashlib
import inspect
import json
import multiprocessing
from concurrent.futures import ProcessPoolExecutor, as_completed
from functools import lru_cache
from pathlib import Path
from typing import Callable

from layered_swim.config import ConfigError, read_bytes, read_text
from layered_swim.outputs import write_text

PACKAGE_DIR = Path(__file__).resolve().parents[1]
DEFAULT_WORKERS = 2     # the machines this project runs on have two cores
# Modules that only present results: editing a plot or a report must not throw the cache away.
PRESENTATION_ONLY = {"cli.py", "analysis/plots.py", "analysis/report.py", "analysis/files.py", "analysis/sweep.py",
                     "analysis/validation_report.py", "analysis/validation_figure.py"}
PRESENTATION_DIRS = ("render/",)   # the window and the video renderer draw runs, never change them
# One module per experiment: each task's own module joins its key, so editing one experiment
# recomputes that experiment only.
TASK_MODULES = "analysis/experiments/"


@lru_cache(maxsize=None)
def code_sha256() -> str:
    """Hash of every source and data file of the package (body file included) that can change
    any simulation's result."""
    digest = hashlib.sha256()
    files = (p for p in PACKAGE_DIR.rglob("*") if p.suffix in (".py", ".yaml") and p.is_file())
    shared = (p for p in files if not _presentation_or_task(p.relative_to(PACKAGE_DIR).as_posix()))
    for path in sorted(shared):
        digest.update(str(path.relative_to(PACKAGE_DIR)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _presentation_or_task(relative: str) -> bool:
    return relative in PRESENTATION_ONLY or relative.startswith((*PRESENTATION_DIRS, TASK_MODULES))


def file_sha256(path: str | Path) -> str:
    return hashlib.sha256(read_bytes(path)).hexdigest()


def cache_key(task: Callable, config: dict) -> str:
    """Hash of the task's name and module source, the configuration and the shared code."""
    module = file_sha256(inspect.getsourcefile(task))
    text = json.dumps({"task": f"{task.__module__}.{task.__qualname__}", "module": module, "config": config,
                       "code": code_sha256()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _load(path: Path):
    try:
        return json.loads(read_text(path))["result"]
    except (ConfigError, ValueError, KeyError, TypeError):
        return None    # missing or half-written: compute it again


def _store(path: Path, config: dict, result) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_text(path, json.dumps({"config": config, "result": result}, allow_nan=False))   # whole or not at all


RAY_INSTALL = "pip install -e '.[ray]'"


def run_sweep(task: Callable[[dict], object], configs: list[dict], cache_dir: str | Path | None = None,
              workers: int = DEFAULT_WORKERS, progress: bool = False, desc: str = "runs",
              ray_address: str | None = None) -> list:
    """``task(config)`` for every configuration, in order; cached ones are read, not run. With
    ``ray_address`` (a Ray cluster's address, or ``local`` for one started here with ``workers``
    CPUs) the jobs run as Ray tasks instead of local processes."""
    paths = [Path(cache_dir) / f"{cache_key(task, c)}.json" if cache_dir is not None else None for c in configs]
    results = [_load(p) if p is not None else None for p in paths]
    todo = [i for i, r in enumerate(results) if r is None]
    if not todo:
        return results
    from tqdm import tqdm

    with tqdm(total=len(configs), initial=len(configs) - len(todo), desc=desc, unit="run", disable=not progress) as bar:
        def done(i: int, result) -> None:
            results[i] = result
            if paths[i] is not None:
                _store(paths[i], configs[i], result)
            bar.update(1)

        workers = max(1, min(workers, len(todo)))
        if ray_address:
            _run_on_ray(task, configs, todo, done, ray_address, workers)
        elif workers == 1:
            for i in todo:
                done(i, task(configs[i]))
        else:
            # Spawned, not forked: a parent that has loaded torch (a policy) hangs forked children.
            with ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn")) as pool:
                futures = {pool.submit(task, configs[i]): i for i in todo}
                for future in as_completed(futures):
                    done(futures[future], future.result())
    return results


def ray_runtime(address: str, workers: int):
    """The ``ray`` module, connected to the cluster at ``address`` (``local``: one started here
    with ``workers`` CPUs) unless already; a one-line error without the [ray] extra."""
    try:
        import ray
    except ImportError:
        raise ConfigError(f"--ray needs the [ray] extra: {RAY_INSTALL}") from None
    if not ray.is_initialized():
        ray.init(address=None if address == "local" else address, num_cpus=workers if address == "local" else None,
                 include_dashboard=False, log_to_driver=False)
    return ray


def _run_on_ray(task, configs: list[dict], todo: list[int], done, address: str, workers: int) -> None:
    ray = ray_runtime(address, workers)
    remote = ray.remote(num_cpus=1)(task)
    pending = {remote.remote(configs[i]): i for i in todo}
    while pending:
        ready, _ = ray.wait(list(pending), num_returns=1)
        done(pending.pop(ready[0]), ray.get(ready[0]))
