"""The SPH solver in a process of its own, and the caller's handle on it.

SPlisHSPlasH keeps global state (one scene per process) and can end the interpreter with exit(),
so it runs in a spawned worker; whatever happens there reaches the caller as one ``FluidError``
line, never as a dead caller. One request, one reply, over a pipe.
"""
from __future__ import annotations

import os
import socket
import subprocess
import sys
import tempfile
import time
import traceback
from multiprocessing.connection import Connection
from pathlib import Path

import numpy as np

from layered_swim.fluid.backend import FluidError

REPLY_TIMEOUT_S = 600.0     # no single request (scene build, settle, step) takes this long
FILL_EXCESS = 0.25          # the block is filled this share of the depth above the surface


def _serve(conn, folder: Path) -> None:
    """The worker's loop: build a scene in ``folder``, then answer steps until told to stop."""
    from layered_swim.fluid.sph.scene import write_scene
    from layered_swim.fluid.sph.solver import INSIDE_MARGIN_RADII, SphSolver

    solver = walls = None
    while True:
        try:
            command, payload = conn.recv()
        except EOFError:
            break
        try:
            if command == "start":
                solver, reply = _start(payload, folder, write_scene, SphSolver, INSIDE_MARGIN_RADII)
                scene = payload["scene"]
                margin = 2 * scene["particle_radius_m"]
                walls = (np.asarray(scene["pool_min_m"]) - margin, np.asarray(scene["pool_max_m"]) + margin)
            elif command == "step":
                *state, want_flow = payload
                force, torque, solver_s = solver.step(*state)
                reply = (force, torque, solver_s, solver.flow_at(state[0]) if want_flow else None,
                         *_water_check(solver, *walls))
            elif command == "particles":
                reply = (solver.positions().copy(), solver.velocities().copy())
            elif command == "stop":
                conn.send(("ok", None))
                break
            else:
                raise ValueError(f"unknown request {command!r}")
            conn.send(("ok", reply))
        except Exception as err:   # noqa: BLE001  every failure goes back as one line
            last = traceback.extract_tb(err.__traceback__)[-1]
            conn.send(("error", f"{type(err).__name__}: {err} (at {Path(last.filename).name}:{last.lineno})"))


def _max_speed(solver) -> float:
    v = solver.velocities()
    return float(np.sqrt(np.einsum("ij,ij->i", v, v).max())) if len(v) else 0.0


def _water_check(solver, lo: np.ndarray, hi: np.ndarray) -> tuple[float, float]:
    """The fastest particle's speed and the share of the water outside the container (a body
    pushed through a wall or the floor can squeeze particles out, and they then fall forever)."""
    x = solver.positions()
    outside = np.count_nonzero(np.any((x < lo) | (x > hi), axis=1))
    return _max_speed(solver), outside / max(1, len(x))


def _start(spec: dict, folder: Path, write_scene, solver_class, margin_radii: float):
    """Build the scene, remove the water inside the boxes, let it settle around them at rest (or,
    with a current, flowing at it), skim what stands above the surface, and let it settle again."""
    started = time.perf_counter()
    scene = spec["scene"]
    r, surface = scene["particle_radius_m"], spec["surface_z_m"]
    # A block on a 2r grid settles to a level below its top (SPH packs it differently), so the
    # block is filled higher and the excess above the surface is skimmed after a first settle.
    depth = surface - scene["pool_min_m"][2]
    path = write_scene(folder / "scene", fill_top_z_m=surface + FILL_EXCESS * depth + 2 * r, **scene)
    solver = solver_class(str(path), str(folder / "output"), scene["boxes_half_m"], scene["time_step_s"],
                          scene["viscosity_m2_s"], r)
    if any(scene["open_axes"]):
        solver.set_current(spec["current_m_s"], scene["pool_min_m"], scene["pool_max_m"], spec["buffer_m"])
    pos, quat = spec["pos_m"], spec["quat_xyzw"]
    solver.place(pos, quat)
    removed = solver.remove_inside(pos, quat, margin_radii * r)
    build_s = time.perf_counter() - started
    # Settle: the block starts on a grid with voids where the boxes were; damping takes the
    # sloshing out (kilonewton spikes otherwise), then a free stretch lets it come to rest.
    steps = int(round(spec["settle_s"] / scene["time_step_s"]))
    _settle(solver, pos, quat, steps // 2, steps // 2, spec["damping_per_step"])
    removed += solver.remove_above(surface)
    force_n = _settle(solver, pos, quat, steps - steps // 2, int(steps * spec["damped_share"]) - steps // 2,
                      spec["damping_per_step"])
    tail = force_n[-max(1, steps // 5):, 2]
    info = {
        "fluid_particles": solver.particles, "boundary_particles": solver.boundary_particles,
        "removed_particles": removed, "build_s": round(build_s, 3), "settle_s": spec["settle_s"],
        "settle_wall_s": round(time.perf_counter() - started - build_s, 3),
        "settled_lift_n": float(tail.mean()), "settled_lift_sd_n": float(tail.std()),
        "max_particle_speed_m_s": _max_speed(solver),
    }
    return solver, info


def _settle(solver, pos, quat, steps: int, damped: int, damping: float) -> np.ndarray:
    """``steps`` steps around the boxes held still, the first ``damped`` with the water's
    velocities scaled by ``damping`` each step; the total force on the boxes per step."""
    zero = np.zeros_like(pos)
    force_n = np.zeros((steps, 3))
    for k in range(steps):
        if k < damped:
            solver.damp(damping)
        force, _, _ = solver.step(pos, quat, zero, zero)
        force_n[k] = force.sum(axis=0)
    return force_n


class SphWorker:
    """The caller's side: start a worker, send requests, turn every failure into a FluidError.

    The worker is a fresh interpreter (``python -m``) on one end of a socket pair: no fork of a
    process that holds PyBullet, and no re-import of the caller's script. The library's console
    chatter goes to a log file, never into the caller's stdout (``--json``). The scene's folder is the
    caller's too, so that a worker that dies (or is killed) leaves nothing behind."""

    def __init__(self, threads: int):
        ours, theirs = socket.socketpair()
        self._folder = tempfile.TemporaryDirectory(prefix="layered_swim_sph_")
        self.log_path = Path(tempfile.mkstemp(prefix="layered_swim_sph_", suffix=".log")[1])
        env = {**os.environ, "OMP_NUM_THREADS": str(threads)}    # OpenMP reads it when it loads
        with theirs, open(self.log_path, "wb") as log:
            self._process = subprocess.Popen(
                [sys.executable, "-m", "layered_swim.fluid.sph.worker", str(theirs.fileno()), self._folder.name],
                pass_fds=(theirs.fileno(),), stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                env=env)
        self._conn = Connection(ours.detach())

    def request(self, command: str, payload=None):
        if self._process is None:
            raise FluidError("the SPH worker has already been stopped")
        try:
            self._conn.send((command, payload))
            if not self._conn.poll(REPLY_TIMEOUT_S):
                raise FluidError(f"the SPH worker did not answer {command!r} within {REPLY_TIMEOUT_S:.0f} s")
            status, reply = self._conn.recv()
        except (EOFError, OSError):
            code = self._process.wait(10)
            self._process = None
            # Its log's last line, not its path: close() deletes the log before anyone reads the message.
            raise FluidError(f"the SPH solver process died during {command!r} (exit code {code}): "
                             f"{self._last_log_line()}") from None
        if status == "error":
            raise FluidError(f"SPH solver failed during {command!r}: {reply}")
        return reply

    def _last_log_line(self) -> str:
        lines = [line for line in self.log_path.read_text(errors="replace").splitlines() if line.strip()]
        return lines[-1].strip() if lines else "no message"

    def close(self) -> None:
        if self._process is not None:
            try:
                self.request("stop")
                self._process.wait(10)
            except (FluidError, subprocess.TimeoutExpired):
                if self._process is not None:
                    self._process.kill()
            self._process = None
        self._conn.close()
        self.log_path.unlink(missing_ok=True)
        self._folder.cleanup()


if __name__ == "__main__":
    _serve(Connection(int(sys.argv[1])), Path(sys.argv[2]))
