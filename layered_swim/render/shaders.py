"""The renderer's GLSL: one program for everything, told by ``kind`` what it draws.

The water is drawn, not simulated: everything is seen through the stretch of water between it and
the eye, which absorbs red first and turns it toward the deep colour, so what lies under the
surface looks under water from above, from the side and from below alike; the surface itself is a
translucent sheet shaded with a few crossing wave trains (its geometry stays flat).
"""
from __future__ import annotations

import math

from layered_swim.sim.simulation import GRAVITY_M_S2  # deep-water waves: omega^2 = g k

PLAIN, BODY, SURFACE, GUIDE = 0, 1, 2, 3     # values of the ``kind`` uniform
# The surface's wave trains: direction (deg from +x), wavelength (m), steepest slope. Crossing at
# odd angles and lengths, so their sum never looks like a grid.
WAVES = ((17.0, 2.3, 0.06), (113.0, 1.37, 0.05), (-56.0, 0.83, 0.045), (205.0, 0.53, 0.04), (71.0, 0.31, 0.03),
         (151.0, 0.19, 0.025))

VERTEX = """#version 330 core
in vec3 position;
in vec3 normal;
in vec4 color;
uniform mat4 view_proj;
out vec3 v_normal;
out vec4 v_color;
out vec3 v_world;
void main() {
    gl_Position = view_proj * vec4(position, 1.0);
    v_normal = normal;
    v_color = color;
    v_world = position;
}
"""

_FRAGMENT = """#version 330 core
in vec3 v_normal;
in vec4 v_color;
in vec3 v_world;
uniform int kind;              // 0 plain, 1 body, 2 water surface, 3 guide (vivid at any depth)
uniform float lit;
uniform vec3 light_dir;
uniform vec3 eye;
uniform vec4 sky;
uniform vec3 deep;
uniform vec3 tint;             // what the first decimetres of water leave of each colour channel
uniform vec3 extinction;       // per metre of water beyond that, per colour channel
uniform float time_s;
out vec4 frag;

const float AIR_HAZE_FROM_M = 25.0;
const float AIR_HAZE_OVER_M = 60.0;
const float WATERLINE_M = 0.012;
const float TINT_M = 0.2;                // the tint is most of the way there after this much water
const float CAUSTIC_M = 2.5;
const float COS_SNELL_WINDOW = 0.66;     // 48.6 deg from the vertical: beyond it the surface is a mirror

// How much of the way from the eye to p runs under the surface (z < 0).
float wet_length(vec3 p) {
    float d = distance(p, eye);
    if ((eye.z < 0.0) == (p.z < 0.0)) return eye.z < 0.0 ? d : 0.0;
    return d * (eye.z < 0.0 ? -eye.z : -p.z) / abs(eye.z - p.z);
}

float haze(float air_m) {
    return clamp((air_m - AIR_HAZE_FROM_M) / AIR_HAZE_OVER_M, 0.0, 1.0);
}

// A colour at p as the eye sees it: through water and air, in the order the eye meets them. Water
// takes red first: quickly a tint (so a hand just under the surface already looks under it), then
// slowly everything, toward the deep colour (so the swimmer stays visible metres away); far air
// fades things into the sky.
vec3 seen_from_eye(vec3 c, vec3 p) {
    float wet = wet_length(p);
    vec3 kept = mix(tint, vec3(1.0), exp(-wet / TINT_M)) * exp(-extinction * wet);
    float hazy = haze(distance(p, eye) - wet);
    if (eye.z >= 0.0) return mix(mix(deep, c, kept), sky.rgb, hazy);
    return mix(deep, mix(c, sky.rgb, hazy), kept);
}

const vec4 WAVES[WAVE_COUNT] = vec4[WAVE_COUNT](WAVE_CONSTANTS);   // wave vector /m; rad/s; amplitude m

// The surface's slope at xy and how it curves there (the Laplacian of its height, per metre),
// which focuses the sunlight below it. Each wave train fades out where it gets finer than the
// pixels (xy changes by ``across`` and ``down`` from one to the next), so far water is smooth
// instead of shimmering.
vec3 ripples(vec2 xy, vec2 across, vec2 down) {
    vec3 slope_curve = vec3(0.0);
    for (int i = 0; i < WAVE_COUNT; i++) {
        vec2 k = WAVES[i].xy;
        float phase = dot(k, xy) - WAVES[i].z * time_s;
        float a = WAVES[i].w * (1.0 - smoothstep(0.6, 2.0, abs(dot(k, across)) + abs(dot(k, down))));
        slope_curve += vec3(a * cos(phase) * k, -a * dot(k, k) * sin(phase));
    }
    return slope_curve;
}

// Sunlight under water, focused where the surface above curves up and spread where it curves
// down (caustics), a pattern that fades as the light goes deeper and blurs (gone by CAUSTIC_M).
float caustic(vec3 p, vec2 across, vec2 down) {
    float depth = -p.z;
    if (depth > CAUSTIC_M) return 1.0;
    return 1.0 + clamp(-1.3 * depth * exp(-depth / 0.5) * ripples(p.xy, across, down).z, -0.3, 0.5);
}

vec4 surface(vec2 across, vec2 down) {
    vec3 to_eye = normalize(eye - v_world);
    vec3 n = normalize(vec3(-ripples(v_world.xy, across, down).xy, 1.0));
    // The ripples' light and shade, exaggerated: a flat sheet would not read as water.
    float sheen = 1.0 + 2.5 * (dot(n, light_dir) - light_dir.z);
    if (eye.z >= 0.0) {
        float fresnel = 0.02 + 0.98 * pow(1.0 - max(dot(n, to_eye), 0.0), 5.0);
        float glint = pow(max(dot(reflect(-to_eye, n), light_dir), 0.0), 80.0);
        vec3 c = mix(v_color.rgb * sheen, sky.rgb, fresnel) + vec3(glint);
        return vec4(seen_from_eye(c, v_world), clamp(mix(v_color.a, 1.0, fresnel) + glint, 0.0, 1.0));
    }
    // From below: the sky through Snell's window overhead; beyond it the surface mirrors the
    // water, a bright rippled ceiling.
    float window = smoothstep(COS_SNELL_WINDOW - 0.1, COS_SNELL_WINDOW + 0.1, -to_eye.z);
    vec3 c = mix(mix(deep, sky.rgb, 0.45) * sheen, mix(sky.rgb, vec3(1.0), 0.4), window);
    return vec4(seen_from_eye(c, v_world), mix(0.9, 0.4, window));
}

void main() {
    vec2 across = dFdx(v_world.xy), down = dFdy(v_world.xy);    // here, where every pixel runs it
    if (kind == 2) {
        frag = surface(across, down);
        return;
    }
    float diffuse = max(dot(normalize(v_normal), light_dir), 0.0);
    vec3 c = v_color.rgb * mix(1.0, 0.4 + 0.6 * diffuse, lit);
    if (kind < 2 && v_world.z < 0.0) c *= caustic(v_world, across, down);
    if (kind == 1) {        // where the surface cuts the body: a bright waterline
        float line = 1.0 - smoothstep(0.0, WATERLINE_M + fwidth(v_world.z), abs(v_world.z));
        c = mix(c, vec3(1.0), 0.85 * line);
    }
    if (kind == 3) {        // guides keep their colour through water; only distance fades them
        frag = vec4(mix(c, eye.z >= 0.0 ? sky.rgb : deep, haze(distance(v_world, eye))), v_color.a);
        return;
    }
    frag = vec4(seen_from_eye(c, v_world), v_color.a);
}
"""


def _waves_glsl() -> str:
    """The wave trains as GLSL constants: deep water, so each runs at sqrt(g k) / k."""
    constants = []
    for direction_deg, wavelength_m, slope in WAVES:
        k = 2 * math.pi / wavelength_m
        kx, ky = k * math.cos(math.radians(direction_deg)), k * math.sin(math.radians(direction_deg))
        constants.append(f"vec4({kx:.4f}, {ky:.4f}, {math.sqrt(GRAVITY_M_S2 * k):.4f}, {slope / k:.5f})")
    return ", ".join(constants)


FRAGMENT = _FRAGMENT.replace("WAVE_COUNT", str(len(WAVES))).replace("WAVE_CONSTANTS", _waves_glsl())
