"""The HUD text: a session in, lines out (no OpenGL, so it is testable on its own)."""
from __future__ import annotations

from layered_swim.control.auto import AUTO
from layered_swim.render.session import SwimSession


def hud_lines(session: SwimSession, fps: float, recording: str = "") -> list[str]:
    s = session
    layers = s.sim.controller.layers
    on = lambda flag: "on " if flag else "off"   # noqa: E731
    weights = ", ".join(f"{name} {w:.2f}" for name, w in sorted(s.weights.items())) or "none"
    current = s.currents[s.current_index]
    density = s.densities[s.density_index]
    if s.paused:
        clock = "PAUSED (N steps, Space resumes)"
    elif s.falling_behind:
        clock = f"SLOWED: the machine keeps {s.realtime_factor:.2f}x real time"
    else:
        clock = f"{s.realtime_factor:.2f}x real time" + (" (slow motion)" if s.slow_motion else "")
    target = "trajectory" if s.target.scripted else f"mouse, depth {s.target_depth_m:.1f} m"
    lines = [
        f"stroke      {s.stroke}" + (f": {s.swimming.name}" if s.stroke == AUTO else ""),
        f"speed       {s.speed_m_s:.2f} m/s    stroke rate {s.stroke_rate_cpm:.0f} /min    phase {s.cycle_phase:.2f}",
        f"weights     {weights}",
        f"layers      basic on  per-cycle {on(layers.cycle)}  palm {on(layers.palm)}  reach {on(layers.reach)}",
        f"fluid       {density.label} ({density.value:g} kg/m3)    current {current.label}"
        + (f"    water {s.flow.name}" if s.flow is not None else ""),
        f"target      {target}    distance {s.distance_to_target_m:.2f} m",
        f"time        {s.sim.time_s:6.1f} s    {clock}    {fps:.0f} FPS",
    ]
    if s.policy is not None:
        lines.insert(4, f"policy      learned residual on the {s.policy.env.reference} controller")
    if recording:
        lines.append(f"REC         {recording}")
    if s.message:
        lines.append(s.message)
    lines.append("H: keys")
    return lines

