"""Runs one experiment: its configurations through the cached parallel sweep, then measures the
results, writes the CSV, draws the figure and writes the report. An experiment module provides

- ``NAME``, ``TITLE``, ``PAPER`` (the paper's finding, in words), ``FIGURE`` and ``CSV`` file names;
- ``configs(quick, seed)``: the runs, as JSON-able dicts (they are also the cache keys);
- ``run(config)``: one simulation, returning a JSON-able result (module level, so it pickles);
- ``measure(configs, results)``: the numbers, as a plain dict; pure (no files, no figure). Its
  ``"rows"`` (dicts with the same keys) become the CSV, one row per run or point; its ``"summary"``
  joins ``summary.json`` beside the text; any other keys (series, the setting's parameters) are
  for ``plot`` and ``describe`` only;
- ``plot(numbers, path)``: draws the figure from the numbers into ``path``;
- ``describe(numbers)``: the report's text from the numbers, an ``Outcome`` (ours, setting, differs);
- optionally ``BACKENDS``, the fluid backends it makes sense on (the plates only by default: a
  sweep of minute-long swims would take days in SPH water). With
  another backend every config carries ``backend`` and ``fluid`` (the backend's settings), which
  ``run`` hands to its episode through ``episode_fluid``.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path

from layered_swim.analysis import report
from layered_swim.analysis.files import write_csv
from layered_swim.analysis.sweep import run_sweep
from layered_swim.config import ConfigError
from layered_swim.outputs import COMMAND_KEY, OutputFolder, claim, write_json, write_text
from layered_swim.runs import versions


@dataclass(frozen=True)
class Outcome:
    """The report's text, which ``describe`` writes from the numbers."""
    ours: str                    # our finding, with our numbers
    setting: str                 # what was simulated
    differs: str | None = None   # where and why ours differs from the paper


def run_experiment(module, out_dir: OutputFolder | str | Path, quick: bool = False, workers: int = 2,
                   progress: bool = False, seed: int = 0, backend: str = "plate", fluid_settings=None,
                   ray_address: str | None = None) -> dict:
    if not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"seed must be a non-negative integer, got {seed!r}")
    backends = getattr(module, "BACKENDS", ("plate",))
    if backend not in backends:
        raise ConfigError(f"experiment {module.NAME} runs on the {' and '.join(backends)} backend only, not {backend}")
    configs = module.configs(quick, seed)
    if backend != "plate":      # plate configs stay as they were: their cached results still count
        fluid = asdict(fluid_settings) if fluid_settings is not None else None
        configs = [{**config, "backend": backend, "fluid": fluid} for config in configs]
    out = claim(out_dir)
    # config.json first: a sweep stopped halfway leaves a folder the next run recognises (and
    # whose cache it reuses), not one it refuses as foreign.
    write_json(out / "config.json", {COMMAND_KEY: "experiment", "experiment": module.NAME, "quick": quick,
                                      "seed": seed, "runs": configs, "versions": versions()})
    results = run_sweep(module.run, configs, out / "cache", workers, progress, desc=module.NAME,
                        ray_address=ray_address)
    numbers = module.measure(configs, results)
    write_csv(out / module.CSV, numbers["rows"])
    module.plot(numbers, out / module.FIGURE)
    outcome = module.describe(numbers)
    summary = {"experiment": module.NAME, "title": module.TITLE, "paper": module.PAPER, "ours": outcome.ours,
               "differs": outcome.differs, "setting": outcome.setting, **numbers["summary"]}
    write_json(out / "summary.json", summary)
    write_text(out / "report.md", report.experiment_report(module.TITLE, module.FIGURE, module.CSV, module.PAPER,
                                                           outcome.ours, outcome.setting, outcome.differs))
    figures = summary.get("figures", [module.FIGURE])      # an experiment may draw more than one
    return {**summary, "files": [*figures, module.CSV, "summary.json", "config.json", "report.md"]}


def episode_fluid(config: dict) -> dict:
    """The ``backend`` and ``fluid_settings`` arguments of an ``Episode`` for this config."""
    backend = config.get("backend", "plate")
    fluid = config.get("fluid")
    if backend != "sph" or fluid is None:
        return {"backend": backend}
    from layered_swim.fluid.sph import SphSettings

    return {"backend": backend, "fluid_settings": SphSettings(**{**fluid, "pool_size_m": tuple(fluid["pool_size_m"])})}
