"""The run log: recorded at a fixed rate, streamed to disk in chunks, read back by one loader.

The format, in one place. A run folder's ``log.npz`` holds one row per log sample (rate
``log_hz`` in its ``config.json``); row k is the state after physics step (k + 1) * (physics_hz /
log_hz), so the first row is one log interval in and every row has real values. Arrays (S
segments in ``segment_names`` order, J motor coordinates in ``joint_names``, P pose angles in
``pose_names``; SI units, world frame, z up, water surface at z = 0):

- ``time_s`` (n,): simulated time.
- ``root_pos_m`` (n, 3), ``root_quat_xyzw`` (n, 4): the pelvis.
- ``com_pos_m`` (n, 3), ``com_vel_m_s`` (n, 3): the whole body's centre of mass.
- ``segment_pos_m`` (n, S, 3), ``segment_quat_xyzw`` (n, S, 4): every segment's centre of mass.
- ``joint_positions`` (n, J): ball joints as quaternions, hinges as angles (rad).
- ``desired_pose_rad`` (n, P): the controller's pose at that time.
- ``fluid_force_n`` (n, S, 3): the fluid force applied during the step that led to the row;
  ``buoyancy_force_n`` (n, S, 3) its buoyancy part (NaN for a backend that cannot separate it).
- ``head_top_m`` (n,): height of the top of the head.
- ``joint_work_j`` (n,), only with ``joint_work``: the joints' mechanical work since the start
  (torque times the mean of the joint rates before and after each physics step, every step;
  power sampled at the log rate would be biased by the PD torque's jumps).

``timeseries.csv`` has the columns ``CSV_COLUMNS`` for a spreadsheet.

While a run goes, full chunks of ``CHUNK_ROWS`` rows are written to ``log.partial/`` and leave
memory; ``save`` joins them into ``log.npz`` one array at a time, so memory stays flat for any
length. A run stopped early (Ctrl-C, a blow-up) saves what it has; one killed outright leaves
the chunks, which ``read_log`` reads too.
"""
from __future__ import annotations

import hashlib
import json
import shutil
import zipfile
import zlib
from pathlib import Path
from typing import Iterator, Mapping

import numpy as np

from layered_swim.config import ConfigError, check_regular_file, load_json
from layered_swim.outputs import atomic_path
from layered_swim.tasks.metrics import head_top_height_m

DEFAULT_LOG_HZ = 60
CHUNK_ROWS = 600          # 10 s at 60 Hz: ~3.5 MB in memory before it goes to disk
SPOOL_DIR = "log.partial"
# Arrays in the order the hash reads them; names come from the recorder, not the simulation.
ARRAY_NAMES = ("time_s", "root_pos_m", "root_quat_xyzw", "com_pos_m", "com_vel_m_s", "segment_pos_m",
               "segment_quat_xyzw", "joint_positions", "desired_pose_rad", "fluid_force_n", "buoyancy_force_n",
               "head_top_m")
OPTIONAL_ARRAY_NAMES = ("joint_work_j",)
NAME_LISTS = ("segment_names", "joint_names", "pose_names")
MAX_LOG_BYTES = 2**40     # any real log fits; the check is that it is a regular file (not a pipe or device)
CSV_COLUMNS = ("time_s", "pelvis_x_m", "pelvis_y_m", "pelvis_z_m", "com_speed_m_s", "head_top_m")


def joint_position_names(layout) -> tuple[str, ...]:
    """Column names of ``World.joint_positions()``: ball joints as quaternions, hinges as angles."""
    names = []
    for is_ball, coord, motor in zip(layout.motor_is_ball, layout.motor_coord, layout.motor_joint):
        names += [f"{motor}.q{c}" for c in "xyzw"] if is_ball else [layout.names[coord]]
    return tuple(names)


def log_hash(arrays: Mapping[str, np.ndarray]) -> str:
    """sha256 over name, dtype, shape and raw bytes of every logged array, in a fixed order."""
    digest = hashlib.sha256()
    for name in ARRAY_NAMES + tuple(n for n in OPTIONAL_ARRAY_NAMES if n in arrays):
        a = np.ascontiguousarray(arrays[name])
        digest.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        digest.update(a.tobytes())
    return digest.hexdigest()


class Recorder:
    """Logs ``sim`` at ``log_hz`` (an observer of ``Episode.run``); with ``spool_dir`` full
    chunks go to disk as the run goes (see the module's docstring)."""

    def __init__(self, sim, log_hz: int = DEFAULT_LOG_HZ, joint_work: bool = False,
                 spool_dir: str | Path | None = None):
        physics_hz = sim.config.physics_hz
        if log_hz <= 0 or physics_hz % log_hz:
            raise ConfigError(f"log rate {log_hz} Hz must divide the physics rate {physics_hz} Hz")
        self.every = physics_hz // log_hz
        self._physics_hz = physics_hz
        body = sim.body
        self.names = {"segment_names": body.segment_names, "joint_names": joint_position_names(sim.layout),
                      "pose_names": sim.layout.names}
        self._head = body.index("head")
        self._head_half_z_m = float(body.half_extents_m[self._head, 2])
        self._rows: dict[str, list] = {name: [] for name in ARRAY_NAMES if name != "head_top_m"}
        self._chunks: list[dict[str, np.ndarray]] = []   # in memory when not spooling
        self.n_chunks = 0
        self._spool = None if spool_dir is None else Path(spool_dir)
        if self._spool is not None:
            shutil.rmtree(self._spool, ignore_errors=True)
            self._spool.mkdir(parents=True)
            (self._spool / "names.json").write_text(json.dumps({k: list(v) for k, v in self.names.items()}))
        self._work_j = None
        if joint_work:
            self._dt_s = 1.0 / physics_hz
            self._work_j, self._rates = 0.0, sim.world.joint_torques_and_rates()[1]
            self._rows["joint_work_j"] = []

    def __call__(self, sim) -> None:
        if self._work_j is not None:
            torque, rates = sim.world.joint_torques_and_rates()
            self._work_j += self._dt_s * float(torque @ (0.5 * (rates + self._rates)))
            self._rates = rates
        if sim.steps % self.every == 0:
            self._record(sim)

    def _record(self, sim) -> None:
        s, rows, fluid = sim.state, self._rows, sim.fluid_now
        rows["time_s"].append(sim.steps / self._physics_hz)   # exact, unlike a running sum of dt
        rows["root_pos_m"].append(s.pos_m[0])
        rows["root_quat_xyzw"].append(s.quat_xyzw[0])
        rows["com_pos_m"].append(s.com_m)
        rows["com_vel_m_s"].append(s.com_vel_m_s)
        rows["segment_pos_m"].append(s.pos_m)
        rows["segment_quat_xyzw"].append(s.quat_xyzw)
        rows["joint_positions"].append(sim.world.joint_positions())
        rows["desired_pose_rad"].append(sim.desired_pose.copy())
        rows["fluid_force_n"].append(fluid.force_n.copy())
        buoyancy = fluid.buoyancy_force_n
        rows["buoyancy_force_n"].append(np.full_like(s.pos_m, np.nan) if buoyancy is None else buoyancy.copy())
        if self._work_j is not None:
            rows["joint_work_j"].append(self._work_j)
        if len(rows["time_s"]) >= CHUNK_ROWS:
            self._flush()

    @property
    def empty(self) -> bool:
        """Nothing logged yet (the run stopped within its first log interval)."""
        return self.n_chunks == 0 and not self._rows["time_s"]

    def _flush(self) -> None:
        if not self._rows["time_s"]:
            return
        chunk = {name: np.array(rows, dtype=float) for name, rows in self._rows.items()}
        chunk["head_top_m"] = head_top_height_m(chunk["segment_pos_m"][:, self._head],
                                                chunk["segment_quat_xyzw"][:, self._head], self._head_half_z_m)
        if self._spool is None:
            self._chunks.append(chunk)
        else:
            # Whole or not at all: a Ctrl-C in the middle leaves the rows here for the final save.
            with atomic_path(self._spool / f"chunk-{self.n_chunks:06d}.npz") as tmp:
                np.savez(tmp, **chunk)
        self.n_chunks += 1
        for rows in self._rows.values():
            rows.clear()

    def _chunk_iter(self, names: tuple[str, ...] | None = None) -> Iterator[dict[str, np.ndarray]]:
        """Every chunk so far; from disk, only ``names`` (all when None) are read."""
        self._flush()
        return iter(self._chunks) if self._spool is None else _spooled_chunks(self._spool, names)

    def arrays(self) -> dict[str, np.ndarray]:
        """The whole log in memory (short runs and analyses)."""
        chunks = list(self._chunk_iter())
        if not chunks:
            raise ConfigError("the run ended before its first log sample")
        return {name: np.concatenate([c[name] for c in chunks]) for name in logged_names(chunks[0])}

    def log_hash(self) -> str:
        return log_hash(self.arrays())

    def save(self, out_dir: str | Path) -> None:
        """Write ``log.npz`` and ``timeseries.csv`` into ``out_dir`` one chunk at a time, each
        file whole or not at all; the spooled chunks are removed once both are in place."""
        out_dir = Path(out_dir)
        chunks = self._chunk_iter
        first = next(chunks(), None)
        if first is None:
            raise ConfigError("the run ended before its first log sample")
        rows = sum(len(c["time_s"]) for c in chunks(("time_s",)))
        with atomic_path(out_dir / "log.npz") as tmp, zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as archive:
            for name in logged_names(first):      # one array at a time: each pass reads only it
                with archive.open(_member(name), "w", force_zip64=True) as member:
                    shape = (rows, *first[name].shape[1:])
                    np.lib.format.write_array_header_2_0(member, {"descr": "<f8", "fortran_order": False,
                                                                  "shape": shape})
                    for chunk in chunks((name,)):
                        member.write(np.ascontiguousarray(chunk[name], dtype="<f8").tobytes())
            for name, values in self.names.items():
                with archive.open(_member(name), "w") as member:
                    np.lib.format.write_array(member, np.array(values))
        with atomic_path(out_dir / "timeseries.csv") as tmp, tmp.open("w") as f:
            f.write(",".join(CSV_COLUMNS) + "\n")
            for c in chunks(("time_s", "root_pos_m", "com_vel_m_s", "head_top_m")):
                table = np.column_stack([c["time_s"], c["root_pos_m"], np.linalg.norm(c["com_vel_m_s"], axis=1),
                                         c["head_top_m"]])
                np.savetxt(f, table, fmt="%.6f", delimiter=",")
        if self._spool is not None:
            shutil.rmtree(self._spool, ignore_errors=True)


def _member(name: str) -> zipfile.ZipInfo:
    """An archive member dated 1980-01-01, not now: the same run gives the same bytes."""
    info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    return info


def logged_names(chunk: Mapping[str, np.ndarray]) -> list[str]:
    """The per-sample arrays in ``chunk`` (a log less its name lists), in the hash's order."""
    return [name for name in ARRAY_NAMES + OPTIONAL_ARRAY_NAMES if name in chunk]


def _spooled_chunks(folder: Path, names: tuple[str, ...] | None = None) -> Iterator[dict[str, np.ndarray]]:
    for path in sorted(folder.glob("chunk-*.npz")):
        with np.load(path, allow_pickle=False) as chunk:
            yield {name: chunk[name] for name in (chunk.files if names is None else names)}


# What a damaged .npz can raise while being read (a bad zip, a bad deflate stream, a bad header).
UNREADABLE_ARCHIVE = (OSError, ValueError, KeyError, EOFError, TypeError, NotImplementedError, zipfile.BadZipFile,
                      zlib.error)


def read_log(run_dir: str | Path) -> dict[str, np.ndarray]:
    """A run folder's log (``log.npz``, or the chunks a killed run left in ``log.partial/``),
    checked: every array present with consistent shapes, times increasing, positions finite.
    Anything else is one ConfigError naming the file; the key ``partial`` is True for chunks."""
    run_dir = Path(run_dir)
    path, spool = run_dir / "log.npz", run_dir / SPOOL_DIR
    try:
        if path.exists():
            check_regular_file(path, MAX_LOG_BYTES)
            with np.load(path, allow_pickle=False) as archive:
                log = {name: archive[name] for name in archive.files}
            log["partial"] = False
        elif spool.is_dir():
            path = spool
            chunks = list(_spooled_chunks(spool))
            if not chunks:
                raise ValueError("no chunks")
            log = {name: np.concatenate([c[name] for c in chunks]) for name in logged_names(chunks[0])}
            names = load_json(spool / "names.json")
            if not isinstance(names, dict):
                raise ConfigError(f"{spool / 'names.json'}: expected the log's name lists, got {type(names).__name__}")
            log.update({k: np.array(v) for k, v in names.items()})
            log["partial"] = True
        else:
            raise ConfigError(f"{run_dir}: no log.npz (a folder written by `layered-swim run` or `follow --out`)")
    except UNREADABLE_ARCHIVE as err:
        raise ConfigError(f"{path}: not a readable log ({_reason(err)})") from None
    _check_log(log, path)
    return log


def _reason(err: Exception) -> str:
    return " ".join(str(err).split())[:120] or type(err).__name__


def _check_log(log: dict, path: Path) -> None:
    missing = [name for name in ARRAY_NAMES + NAME_LISTS if name not in log]
    if missing:
        raise ConfigError(f"{path}: not a layered-swim log (no {', '.join(missing)})")
    for name in NAME_LISTS:
        names = log[name]
        if names.ndim != 1 or names.size == 0 or names.dtype.kind != "U":
            raise ConfigError(f"{path}: {name} must be a non-empty list of names, got shape {names.shape} "
                              f"({names.dtype})")
    n, segments = len(log["time_s"]), len(log["segment_names"])
    expected = {"time_s": (n,), "root_pos_m": (n, 3), "com_pos_m": (n, 3), "com_vel_m_s": (n, 3),
                "segment_pos_m": (n, segments, 3), "segment_quat_xyzw": (n, segments, 4),
                "fluid_force_n": (n, segments, 3), "head_top_m": (n,)}
    for name, shape in expected.items():
        array = log[name]
        if array.shape != shape or array.dtype.kind != "f":
            raise ConfigError(f"{path}: {name} has shape {array.shape} ({array.dtype}), expected {shape} floats")
    if n == 0 or not np.all(np.diff(log["time_s"]) > 0):
        raise ConfigError(f"{path}: time_s is empty or not increasing")
    for name in ("time_s", "com_pos_m", "segment_pos_m", "segment_quat_xyzw"):
        if not np.isfinite(log[name]).all():
            raise ConfigError(f"{path}: {name} has NaN or infinite values (the run blew up before this sample?)")
