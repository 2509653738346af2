"""Real swimmers' ranges from ``layered_swim/reference.md`` (section 3), per stroke,
and the verdict of a measured number against them (inside / below / above); and, in one table,
the targets issue 36 sets the model (``MUST_HOLD``, ``must_hold``), each with its source.

Only its numbers are used; a quantity it gives no range for gets none here, and
the report says so rather than inventing one. An open-ended range has an infinite bound.
"""
from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Range:
    low: float
    high: float
    source: str

    def verdict(self, value: float | None) -> str:
        if value is None:
            return "n/a"
        return "below" if value < self.low else "above" if value > self.high else "inside"


PEAK_HAND_FORCE = Range(70.0, 150.0, "peak hand force, typical studies (R)")
BREASTSTROKE_SPEED = Range(0.6, 1.0, "recreational breaststroke speed (R)")


def up_to_record(record_m_s: float, stroke: str) -> Range:
    """The sheet gives no recreational speed for backstroke or butterfly: a real swimmer's speed
    lies between the slowest recreational speed it gives for any stroke (breaststroke's) and the
    stroke's 100 m world record."""
    return Range(BREASTSTROKE_SPEED.low, record_m_s, f"slowest recreational speed of any stroke "
                 f"({BREASTSTROKE_SPEED.low:g}, breaststroke) to the 100 m {stroke} world record's mean")


RANGES: dict[str, dict[str, Range]] = {
    "front_crawl": {
        "mean_speed_m_s": Range(0.8, 1.2, "recreational crawl speed (R)"),
        "stroke_rate_cpm": Range(50.0, 55.0, "elite freestyle stroke rate (Hay 1984)"),
        "distance_per_cycle_m": Range(2.2, 2.5, "elite freestyle distance per cycle (Hay 1984)"),
        "speed_fluctuation_pct": Range(15.0, 20.0, "crawl intracycle speed fluctuation +-15-20 % "
                                                   "(Craig & Pendergast 1979)"),
        "shoulder_roll_deg": Range(45.0, 60.0, "front-crawl shoulder roll per side (Psycharakis & Sanders 2010)"),
        "hip_roll_deg": Range(30.0, 45.0, "front-crawl hip roll per side (Psycharakis & Sanders 2010)"),
        "peak_hand_force_n": PEAK_HAND_FORCE,
    },
    "breaststroke": {
        "mean_speed_m_s": BREASTSTROKE_SPEED,
        "stroke_rate_cpm": Range(50.0, 60.0, "elite breaststroke stroke rate (Hay 1984)"),
        "distance_per_cycle_m": Range(1.8, 2.0, "elite breaststroke distance per cycle (Hay 1984)"),
        "speed_fluctuation_pct": Range(45.0, 50.0, "breaststroke intracycle speed fluctuation +-45-50 % "
                                                   "(Craig & Pendergast 1979)"),
        "peak_hand_force_n": PEAK_HAND_FORCE,
    },
    "backstroke": {
        "mean_speed_m_s": up_to_record(1.94, "backstroke"),
        "stroke_rate_cpm": Range(45.0, 50.0, "elite backstroke stroke rate (Hay 1984)"),
        "distance_per_cycle_m": Range(2.2, 2.4, "elite backstroke distance per cycle (Hay 1984)"),
        "speed_fluctuation_pct": Range(15.0, 20.0, "backstroke intracycle speed fluctuation +-15-20 % "
                                                   "(Craig & Pendergast 1979)"),
        "shoulder_roll_deg": Range(40.0, 50.0, "backstroke shoulder roll per side (R)"),
        "peak_hand_force_n": PEAK_HAND_FORCE,
    },
    "butterfly": {
        "mean_speed_m_s": up_to_record(2.02, "butterfly"),
        "stroke_rate_cpm": Range(50.0, 55.0, "elite butterfly stroke rate (Hay 1984)"),
        "distance_per_cycle_m": Range(2.0, 2.1, "elite butterfly distance per cycle (Hay 1984)"),
        "speed_fluctuation_pct": Range(45.0, 50.0, "butterfly intracycle speed fluctuation +-45-50 % "
                                                   "(Craig & Pendergast 1979)"),
        "peak_hand_force_n": PEAK_HAND_FORCE,
    },
    "treading_water": {
        # The sheet says "~1 Hz leg cycles"; +-10 % around it is our reading of "~".
        "stroke_rate_cpm": Range(54.0, 66.0, "eggbeater leg cycles ~1 Hz (E/R), +-10 %"),
    },
}

# Narita et al. 2017 (D = 32.2 v^3.3 N) and Cortesi et al. 2024 (~38 v^2 N) measured active drag
# on real swimmers; at a given speed the two bound the range we compare with.
ACTIVE_DRAG_LAWS = ((32.2, 3.3, "Narita et al. 2017"), (38.0, 2.0, "Cortesi et al. 2024"))


def active_drag_range(speed_m_s: float) -> Range:
    values = [k * abs(speed_m_s) ** p for k, p, _ in ACTIVE_DRAG_LAWS]
    names = " and ".join(f"{k:g} v^{p:g} N ({who})" for k, p, who in ACTIVE_DRAG_LAWS)
    return Range(min(values), max(values), f"active drag at this speed, between {names}")


def ranges_for(stroke: str, speed_m_s: float | None) -> dict[str, Range]:
    """Every range that applies to ``stroke`` (none for strokes the sheet does not cover)."""
    out = dict(RANGES.get(stroke, {}))
    if speed_m_s is not None and stroke in ("front_crawl", "breaststroke"):
        out["active_drag_n"] = active_drag_range(speed_m_s)
    return out


def at_most(high: float, source: str) -> Range:
    return Range(-math.inf, high, source)


def at_least(low: float, source: str) -> Range:
    return Range(low, math.inf, source)


def within(limit: float, source: str) -> Range:
    return Range(-limit, limit, source)


# Real swimmers' figures `validate strokes` adds to RANGES (reference.md section 3).
PROPELLING_EFFICIENCY = Range(0.3, 0.7, "front-crawl propelling efficiency: ~0.3-0.4 Froude efficiency (Zamparo et "
                                        "al. 2005) to ~0.45-0.6 with the MAD system (Toussaint et al. 1988) (R)")
VALIDATION_RANGES: dict[str, dict[str, Range]] = {
    "front_crawl": {"propelling_efficiency": PROPELLING_EFFICIENCY},
    "treading_water": {"head_top_above_time_pct": Range(100.0, 100.0, "treading water holds the head up (E, R)")},
}

# Issue 36: what the model must reach (reference.md section 6), the one table of its targets.
# Each names the issue and the figure of reference.md it comes from, where it comes from one.
ISSUE = "issue 36 target"
MUST_HOLD: dict[str, dict[str, Range]] = {
    "front_crawl": {
        "mean_speed_m_s": Range(1.2, 1.8, f"{ISSUE}: a trained crawl, above recreational 0.8-1.2 m/s (R)"),
        "peak_hand_force_n": Range(70.0, 200.0, f"{ISSUE}: peak hand force 70-150 N typical, 200-300 elite (R)"),
        "pitch_deg": within(6.0, f"{ISSUE}: a level body"),
        "body_inclination_deg": within(6.0, f"{ISSUE}: a level body, the legs too (a level pelvis with the legs "
                                            "hanging is not)"),
        "shoulder_roll_deg": Range(40.0, 60.0, f"{ISSUE}: shoulder roll 45-60 deg per side (Psycharakis & "
                                               "Sanders 2010)"),
        "distance_per_cycle_m": at_least(1.8, f"{ISSUE}: elite 2.2-2.5 m (Hay 1984)"),
        "joint_power_w": at_most(500.0, f"{ISSUE}: the joints' net mechanical power"),
    },
    "breaststroke": {
        "mean_speed_m_s": Range(0.8, 1.4, f"{ISSUE}: recreational 0.6-1.0 m/s (R) to faster"),
        "peak_hand_force_n": at_most(200.0, f"{ISSUE}: peak hand force 70-150 N typical (R)"),
        "pitch_deg": within(12.0, f"{ISSUE}: breaststroke rides higher, still near level"),
        "body_inclination_deg": within(12.0, f"{ISSUE}: breaststroke rides higher, still near level, the legs too"),
        "face_breath_cycles_pct": Range(100.0, 100.0, f"{ISSUE}: the head above water once a cycle, to breathe"),
    },
    "backstroke": {
        "face_under_time_pct": Range(0.0, 0.0, f"{ISSUE}: a backstroker's face never goes under"),
    },
    "butterfly": {
        "peak_hand_force_n": at_most(200.0, f"{ISSUE}: peak hand force 70-150 N typical (R)"),
        "distance_per_cycle_m": at_least(1.8, f"{ISSUE}: elite 2.0-2.1 m (Hay 1984)"),
    },
}
# Front crawl's active drag (velocity perturbation method) within these multiples of Narita et al.
# 2017's measured 32.2 v^3.3 N at the swimmer's own speed.
ACTIVE_DRAG_TARGET_X = (0.7, 1.5)
ACTIVE_DRAG_TARGET_STROKES = ("front_crawl",)


def must_hold(stroke: str, speed_m_s: float | None) -> dict[str, Range]:
    """Issue 36's targets for ``stroke`` (the active drag's at ``speed_m_s``)."""
    out = dict(MUST_HOLD.get(stroke, {}))
    if speed_m_s is not None and stroke in ACTIVE_DRAG_TARGET_STROKES:
        k, power, who = ACTIVE_DRAG_LAWS[0]
        narita = k * abs(speed_m_s) ** power
        low, high = ACTIVE_DRAG_TARGET_X
        out["active_drag_n"] = Range(low * narita, high * narita, f"{ISSUE}: {low:g}-{high:g} x {k:g} v^{power:g} N "
                                                                  f"at this speed ({who}, M)")
    return out
