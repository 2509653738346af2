"""SPlisHSPlasH (DFSPH, Akinci 2012 boundaries) driven body by body: the only module that imports
``pysplishsplash``. It runs inside the SPH worker process (``worker.py``): the library keeps global
state and can end the interpreter, so it never shares a process with the caller.

Per step: every box gets the pose and velocity PyBullet computed, the fluid advances one step,
and the force and torque the fluid put on each box are read back. SPlisHSPlasH's own rigid-body
solver is never stepped, so the boxes go exactly where PyBullet says.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import time

import numpy as np
from scipy.spatial.transform import Rotation

from layered_swim.fluid.sph import conveyor
from layered_swim.geometry import quat_multiply

INSIDE_MARGIN_RADII = 2.0   # particles closer than this to a box are removed (one radius left ~100 m/s jets)


def import_sph():
    """Import pysplishsplash. Its wheel bundles a libGLdispatch that clashes with the system's
    libGLX (a segfault on import); loading the system's first avoids it."""
    name = ctypes.util.find_library("GLdispatch")
    if name:
        ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
    import pysplishsplash
    import pysplishsplash.Utilities  # noqa: F401  (registers the submodules)
    return pysplishsplash


class SphSolver:
    """One SPlisHSPlasH scene: the water and ``n`` dynamic boxes (the last ``n`` boundary models;
    the pool's walls come first)."""

    def __init__(self, scene_file: str, output_dir: str, half_extents_m: np.ndarray, time_step_s: float,
                 viscosity_m2_s: float, particle_radius_m: float):
        sph = import_sph()
        self.base = base = sph.Exec.SimulatorBase()
        base.init(sceneFile=scene_file, useGui=False, useCache=False, outputDir=output_dir, initialPause=False)
        base.initSimulation()
        self.sim = sim = sph.Simulation.getCurrent()
        self.fluid = sim.getFluidModel(0)
        self._set_viscosity(viscosity_m2_s)
        # The deferred initialisation (boundary sampling and volumes) is not bound in Python: a
        # run that stops after one step does it (a negative stop time without a GUI calls exit()).
        base.setValueFloat(base.STOP_AT, float(time_step_s) / 2)
        base.runSimulation()
        base.setValueFloat(base.STOP_AT, -1.0)
        sph.TimeManager.getCurrent().setTimeStepSize(float(time_step_s))
        self.dt = float(time_step_s)
        self.half = np.asarray(half_extents_m, dtype=float)
        self.flow_margin_m = 2 * particle_radius_m
        first = sim.numberOfBoundaryModels() - len(self.half)
        self.bodies = [sim.getBoundaryModel(first + k).getRigidBodyObject() for k in range(len(self.half))]
        self.boundary_sim = base.getBoundarySimulator()
        self.mass = np.array([b.getMass() for b in self.bodies])
        # Each body is kept in its principal-axes frame: body rotation = ours * offset^-1, with the
        # constant offset read off at init (the boxes start unrotated in the scene).
        offset_inv, inertia = [], []
        for body in self.bodies:
            principal = Rotation.from_quat(body.getRotation())               # (x, y, z, w), as PyBullet's
            mesh = Rotation.from_matrix(np.asarray(body.getWorldSpaceRotation()))
            offset_inv.append((principal.inv() * mesh).inv().as_quat())
            inertia.append(self._measure_inertia(body, principal))
        self._offset_inv, self._inertia_body = np.array(offset_inv), np.array(inertia)
        self.boundary_particles = sum(sim.getBoundaryModel(k).numberOfParticles()
                                      for k in range(sim.numberOfBoundaryModels()))
        self.current = np.zeros(3)
        self._conveyor = None

    def set_current(self, current_m_s, water_min_m, water_max_m, buffer_m: float) -> None:
        """Drive a horizontal current through the pool's open ends (``conveyor.py``). The water's
        particles are then never re-sorted in memory (SPlisHSPlasH's z-sort would reorder them
        between our buffer bookkeeping before and after a step)."""
        self.current = np.asarray(current_m_s, dtype=float)
        self._conveyor = (np.asarray(water_min_m, float), np.asarray(water_max_m, float),
                          conveyor.open_axes(current_m_s), buffer_m)
        self.sim.setValueBool(self.sim.ENABLE_Z_SORT, False)

    def _set_viscosity(self, viscosity_m2_s: float) -> None:
        """Set on the model too: the scene file's key for it has moved between releases."""
        if viscosity_m2_s > 0:
            self.fluid.setValueInt(self.fluid.VISCOSITY_METHOD, 1)   # standard (XSPH-like) viscosity
            visc = self.fluid.getViscosityBase()
            visc.setValueFloat(visc.VISCOSITY_COEFFICIENT, float(viscosity_m2_s))
        else:
            self.fluid.setValueInt(self.fluid.VISCOSITY_METHOD, 0)

    def _measure_inertia(self, body, principal) -> np.ndarray:
        """The body's inertia tensor in its principal frame, from its response to unit torques."""
        inverse = np.empty((3, 3))
        for k in range(3):
            body.setAngularVelocity([0.0, 0.0, 0.0])
            body.addTorque(list(np.eye(3)[k]))
            inverse[:, k] = np.asarray(body.getAngularVelocity()) / self.dt
        body.setAngularVelocity([0.0, 0.0, 0.0])
        r = principal.as_matrix()
        return np.linalg.inv(r.T @ inverse @ r)

    # -- the water ----------------------------------------------------------------------------
    @property
    def particles(self) -> int:
        return self.fluid.numActiveParticles()

    def positions(self) -> np.ndarray:
        return np.asarray(self.fluid.getFieldBuffer("position"))[: self.particles]

    def velocities(self) -> np.ndarray:
        return np.asarray(self.fluid.getFieldBuffer("velocity"))[: self.particles]

    def flow_at(self, centres_m) -> np.ndarray:
        """The mean water velocity around each box (particles within its largest half extent plus
        two radii of its centre; zero where there is none), (n, 3)."""
        reach = self.half.max(axis=1) + self.flow_margin_m
        centres = np.asarray(centres_m, dtype=np.float32)
        x, v = self.positions(), self.velocities()
        # One pass keeps the particles around the swimmer; the per-box passes see only those.
        around = np.all((x > centres.min(axis=0) - reach.max()) & (x < centres.max(axis=0) + reach.max()), axis=1)
        x, v = x[around], v[around]
        flow = np.zeros((len(self.half), 3))
        for k, centre in enumerate(centres):
            d = x - centre
            near = np.einsum("ij,ij->i", d, d) < reach[k] ** 2
            if near.any():
                flow[k] = v[near].mean(axis=0)
        return flow

    def place(self, pos_m, quat_xyzw, linvel_m_s=None, angvel_rad_s=None) -> float:
        """Put every box where PyBullet has it (world frame, centre and orientation); returns the
        seconds SPlisHSPlasH took to move the boundary particles."""
        n = len(self.bodies)
        linvel = np.zeros((n, 3)) if linvel_m_s is None else linvel_m_s
        angvel = np.zeros((n, 3)) if angvel_rad_s is None else angvel_rad_s
        principal = quat_multiply(np.asarray(quat_xyzw, dtype=float), self._offset_inv).tolist()
        pos, linvel, angvel = (np.asarray(pos_m, float).tolist(), np.asarray(linvel).tolist(),
                               np.asarray(angvel).tolist())
        for k, body in enumerate(self.bodies):
            body.setPosition(pos[k])
            body.setRotation(principal[k])
            body.setVelocity(linvel[k])
            body.setAngularVelocity(angvel[k])
        return self._timed(self.base.updateBoundaryParticles, False)

    def remove_inside(self, pos_m, quat_xyzw, margin_m: float) -> int:
        """Remove the water inside (and within ``margin_m`` of) the boxes at this pose. Returns
        how many particles went."""
        x = self.positions().astype(float)
        keep = np.ones(len(x), dtype=bool)
        rotations = Rotation.from_quat(quat_xyzw).as_matrix()
        for k in range(len(self.bodies)):
            local = (x - pos_m[k]) @ rotations[k]     # world -> box frame
            keep &= ~np.all(np.abs(local) < self.half[k] + margin_m, axis=1)
        return self.keep(keep)

    def remove_above(self, z_m: float) -> int:
        """Remove the water above height ``z_m`` (the fill's excess over the surface)."""
        return self.keep(self.positions()[:, 2] < z_m)

    def keep(self, mask: np.ndarray) -> int:
        """Keep only the particles in ``mask`` and restart the fluid from them, where they are
        now and at rest (SPlisHSPlasH's reset puts particles back at their stored start
        positions: those become the present ones). Returns how many particles went."""
        count, total = int(mask.sum()), len(mask)
        position = np.asarray(self.fluid.getFieldBuffer("position"))
        kept = position[:total][mask].copy()
        position[:count] = kept
        np.asarray(self.fluid.getFieldBuffer("position0"))[:count] = kept
        self.fluid.setNumActiveParticles0(count)
        self.fluid.reset()
        np.asarray(self.fluid.getFieldBuffer("velocity"))[:count] = self.current    # at rest in the current
        return total - count

    def damp(self, factor: float) -> None:
        """Scale every particle's velocity relative to the current (the settle phase)."""
        velocity = np.asarray(self.fluid.getFieldBuffer("velocity"))[: self.particles]
        velocity[:] = self.current + (velocity - self.current) * factor

    def step(self, pos_m, quat_xyzw, linvel_m_s, angvel_rad_s) -> tuple[np.ndarray, np.ndarray, float]:
        """Advance the water one step around the boxes at this state. Returns the fluid's force (N)
        and torque (N m, about each box centre) on every box, world frame, and the seconds spent
        inside SPlisHSPlasH's own calls (boundary update, fluid step, force gathering)."""
        solver_s = self.place(pos_m, quat_xyzw, linvel_m_s, angvel_rad_s)
        if self._conveyor is None:
            solver_s += self._timed(self.sim.getTimeStep().step)
        else:
            solver_s += self._conveyor_step()
        force, torque, gather_s = self._read_wrenches(quat_xyzw)
        return force, torque, solver_s + gather_s

    def _conveyor_step(self) -> float:
        """One step with the open ends' buffers moved rigidly at the current, and the water that
        left through one end put back in through the other; the seconds the solver took."""
        lo, hi, axes, buffer_m = self._conveyor
        n = self.particles
        position = np.asarray(self.fluid.getFieldBuffer("position"))[:n]
        velocity = np.asarray(self.fluid.getFieldBuffer("velocity"))[:n]
        conveyor.wrap(position, lo, hi, axes)
        driven = conveyor.in_buffers(position, lo, hi, axes, buffer_m)
        start = position[driven] + (self.current * self.dt).astype(position.dtype)
        velocity[driven] = self.current
        seconds = self._timed(self.sim.getTimeStep().step)
        position[driven] = start
        velocity[driven] = self.current
        return seconds

    @staticmethod
    def _timed(call, *args) -> float:
        start = time.perf_counter()
        call(*args)
        return time.perf_counter() - start

    def _read_wrenches(self, quat_xyzw) -> tuple[np.ndarray, np.ndarray, float]:
        # getForceAndTorque's numpy outputs stay zero (the binding copies its out-arguments), so
        # the accumulated wrench is read through the velocity change it gives a body at rest:
        # updateBoundaryForces() integrates it (v += F dt / m, w += I_w^-1 tau dt) and clears it.
        for body in self.bodies:
            body.setVelocity([0.0, 0.0, 0.0])
            body.setAngularVelocity([0.0, 0.0, 0.0])
        gather_s = self._timed(self.boundary_sim.updateBoundaryForces)
        velocity = np.array([body.getVelocity() for body in self.bodies])
        spin = np.array([body.getAngularVelocity() for body in self.bodies])
        force = self.mass[:, None] * velocity / self.dt
        r = Rotation.from_quat(quat_multiply(np.asarray(quat_xyzw, dtype=float), self._offset_inv)).as_matrix()
        # tau = I_w dw / dt with I_w = R I_principal R^T.
        local = np.einsum("nji,nj->ni", r, spin)
        torque = np.einsum("nij,nj->ni", r, np.einsum("nij,nj->ni", self._inertia_body, local)) / self.dt
        return force, torque, gather_s
