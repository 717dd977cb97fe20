// What every pass shares, prepended to each shader: the frame's globals
// (group 0), the cut plane's test and the endoscope's light at the eye.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: the eye; w: a typical depth, for the light's falloff.
    eye: vec4<f32>,
    // xyz: the cut plane's normal, w: its offset; points with
    // dot(n, p) > w are cut away. A zero normal cuts nothing.
    clip: vec4<f32>,
    // x: bump on (1) or off (0); y: heat map (1) or texture (0).
    flags: vec4<f32>,
}

@group(0) @binding(0) var<uniform> globals: Globals;

fn clipped(p: vec3<f32>) -> bool {
    return dot(globals.clip.xyz, globals.clip.xyz) > 0.0 && dot(globals.clip.xyz, p) > globals.clip.w;
}

// Light at the eye on a surface at `p` with unit normal `n`, two-sided,
// fading with distance.
fn headlamp(n: vec3<f32>, p: vec3<f32>) -> f32 {
    let to_eye = globals.eye.xyz - p;
    let d = length(to_eye);
    let falloff = 1.0 / (1.0 + pow(d / (1.5 * globals.eye.w), 2.0));
    return (0.15 + 0.85 * abs(dot(n, to_eye / max(d, 1e-20)))) * (0.4 + 1.2 * falloff);
}
