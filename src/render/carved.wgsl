// Faces a carving exposed (organtex::runtime::Carving): each textured
// from its page of the cut-texture atlas, whose texels are the interior's
// colours, lit like the facets and cuts.

struct Globals {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    clip: vec4<f32>,
    flags: vec4<f32>,
}

@group(0) @binding(0) var<uniform> globals: Globals;
@group(1) @binding(0) var page: texture_2d<f32>;
@group(1) @binding(1) var page_sampler: sampler;

struct CarvedIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct CarvedOut {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

@vertex
fn vs_carved(v: CarvedIn) -> CarvedOut {
    var out: CarvedOut;
    out.clip_position = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.uv = v.uv;
    return out;
}

@fragment
fn fs_carved(in: CarvedOut) -> @location(0) vec4<f32> {
    if dot(globals.clip.xyz, globals.clip.xyz) > 0.0 && dot(globals.clip.xyz, in.world) > globals.clip.w {
        discard;
    }
    let to_eye = globals.eye.xyz - in.world;
    let d = length(to_eye);
    let falloff = 1.0 / (1.0 + pow(d / (1.5 * globals.eye.w), 2.0));
    let light = (0.15 + 0.85 * abs(dot(normalize(in.normal), to_eye / max(d, 1e-20)))) * (0.4 + 1.2 * falloff);
    // The page is sRGB: sampling decodes it to linear light.
    return vec4<f32>(textureSampleLevel(page, page_sampler, in.uv, 0.0).rgb * light, 1.0);
}
