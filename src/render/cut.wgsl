// Cut surfaces: each point coloured from the organ's interior solid
// texture (block_colour, from solid/sample_block.wgsl, prepended to this
// file), lit like the facets.

struct Globals {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    clip: vec4<f32>,
    flags: vec4<f32>,
}

@group(0) @binding(0) var<uniform> globals: Globals;

struct CutIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

struct CutOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
}

@vertex
fn vs_cut(v: CutIn) -> CutOut {
    var out: CutOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    return out;
}

// The block holds sRGB-encoded bytes read as they are (sample_block.wgsl);
// the target encodes linear light, so decode first.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    return select(pow((c + 0.055) / 1.055, vec3<f32>(2.4)), c / 12.92, c <= vec3<f32>(0.04045));
}

@fragment
fn fs_cut(in: CutOut) -> @location(0) vec4<f32> {
    let to_eye = globals.eye.xyz - in.world;
    let d = length(to_eye);
    let falloff = 1.0 / (1.0 + pow(d / (1.5 * globals.eye.w), 2.0));
    let light = (0.15 + 0.85 * abs(dot(normalize(in.normal), to_eye / max(d, 1e-20)))) * (0.4 + 1.2 * falloff);
    return vec4<f32>(srgb_to_linear(block_colour(in.world)) * light, 1.0);
}
